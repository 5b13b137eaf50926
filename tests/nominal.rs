//! MODEL.md §3.4 nominal values (1e-9 relative) and §4 object properties.
use crate::common::*;
use gripopt::model::closed_pose;
use gripopt::model::singularity_sweep;
use gripopt::model::Finger;

const REL: f64 = 1e-9;

#[test]
fn derived_lengths_and_open_pose() {
    let s = scene();
    let x = nominal();
    close_rel(x.t22, 0.0376, 1e-12, "t22");
    close_rel(x.l_hand(), 0.230, 1e-12, "l_hand");
    close_rel(x.psi.to_degrees(), 129.76, 1e-12, "psi");
    let f = Finger::new(&x, &s).unwrap();
    close_rel(f.l11, 0.01976, REL, "l11");
    close_rel(f.l22, 0.0090896, REL, "l22");
    close_rel(f.l12, 0.045419424436, REL, "l12");
    close_rel(f.k10, 0.016093476939, REL, "k10");
    close_rel(f.open.q11.to_degrees(), -44.441240127, REL, "q11_0");
    close_rel(f.open.q21.to_degrees(), 45.558759873, REL, "q21_0");
    close_rel(f.open.q12.to_degrees(), 106.332636305, REL, "q12_0");
    close_rel(f.open.q22.to_degrees(), -129.76, REL, "q22_0");
    close_rel(f.open.q13.to_degrees(), -146.092636305, REL, "q13_0");
    assert_eq!(f.gamma, 1.0);
    assert_eq!(f.sigma, 1.0);
}

#[test]
fn mass_properties() {
    let f = Finger::new(&nominal(), &scene()).unwrap();
    let m = [2.141686543805e-3, 4.922781889786e-3, 5.354216359513e-3, 5.060449800387e-3];
    let i = [2.921314701809e-7, 3.415875879736e-6, 4.388868997281e-6, 1.979246277171e-6];
    for k in 0..4 {
        close_rel(f.mass.m[k], m[k], REL, &format!("m[{k}]"));
        close_rel(f.mass.i[k], i[k], REL, &format!("I[{k}]"));
    }
    close_rel(f.mass.s22.x, -8.798342151567e-3, REL, "x_S22");
    close_rel(f.mass.s22.y, 1.163856653168e-2, REL, "y_S22");
}

#[test]
fn object_properties() {
    let s = scene();
    close_rel(s.object.mass(), 1.005310, 1e-6, "m_c");
    close_rel(s.object.inertia(), 3.75316e-3, 1e-5, "J_c");
    close_rel(s.object.impulse_lever(), 0.05, 1e-12, "k_c");
}

#[test]
fn closed_pose_on_40mm() {
    let s = scene();
    let f = Finger::new(&nominal(), &s).unwrap();
    let cp = closed_pose(&f, 0.040, 0.0).unwrap();
    close_rel(cp.theta1.to_degrees(), 57.825595319, REL, "theta1");
    close_rel(cp.theta2.to_degrees(), 68.174528183, REL, "theta2");
    close_rel(cp.k1, 0.018947295321, REL, "k1");
    close_rel(cp.k2, 0.030452704679, REL, "k2");
    close_rel(cp.pose.q11.to_degrees(), -4.104849277, REL, "q11");
    close_rel(cp.pose.q12.to_degrees(), 73.927843801, REL, "q12");
    close_rel(cp.pose.q22.to_degrees(), -61.585471817, REL, "q22");
    close_rel(cp.pose.q13.to_degrees(), -73.582871023, REL, "q13");
}

#[test]
fn nominal_singularity_margin() {
    let s = scene();
    let f = Finger::new(&nominal(), &s).unwrap();
    let sw = singularity_sweep(&f, &s).unwrap();
    close_rel(sw.min_margin.to_degrees(), 33.907363695, 1e-9, "min margin");
    assert_eq!(sw.at_theta2, 0.0);
}
