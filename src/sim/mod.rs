//! Simulation: integrators, the grasp scene, and the dynamic criteria (MODEL.md §8–9).

pub mod criteria;
pub mod finger;
pub mod grasp;
pub mod integrator;
