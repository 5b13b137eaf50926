//! Shared helpers for the integration tests.
#![allow(dead_code)]

use gripopt::params::{Design, Problem, SceneParams};

/// The default problem, loaded from the repository file.
pub fn bottle() -> Problem {
    Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).expect("bottle-1l.toml loads")
}

/// The nominal scene.
pub fn scene() -> SceneParams {
    bottle().scene
}

/// The nominal design.
pub fn nominal() -> Design {
    Design::nominal()
}

/// Assert |a − b| ≤ rel·|b| with a message.
#[track_caller]
pub fn close_rel(a: f64, b: f64, rel: f64, what: &str) {
    assert!((a - b).abs() <= rel * b.abs(), "{what}: got {a:.15e}, expected {b:.15e} (rel {:.2e})", (a - b).abs() / b.abs());
}

/// Assert |a − b| ≤ abs.
#[track_caller]
pub fn close_abs(a: f64, b: f64, abs: f64, what: &str) {
    assert!((a - b).abs() <= abs, "{what}: got {a:.15e}, expected {b:.15e} (diff {:.2e})", (a - b).abs());
}

/// A design drawn uniformly in the default box of bottle-1l.toml.
pub fn random_design<R: rand::Rng>(rng: &mut R) -> Design {
    bottle().bounds.sample(rng)
}
