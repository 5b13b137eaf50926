//! Simulation (MODEL.md §8–9): integrators, events, the generic step loop, scenes, the
//! finger model, contact memory, criteria.
//!
//! Layout (private modules, re-exported flat): `integrate/` (one file per method, LU,
//! finite-difference Jacobian, block elimination of Newton matrices, Hermite dense output)
//! → `events` (kinds, crossing rules, root locator) → `driver` (the step loop, generic over
//! a [`Scene`]) ← `scene/` (what is integrated: the centred scene [`CentredScene`], the
//! offset and the free scene, `contact3d` its 3-D contacts) built from `finger` (one finger
//! against a given object), `memory` (the contact-memory rule), `tracking` (criteria during
//! a grasp), `equilibrium` (§8.9) and `criteria` (§9); `result` holds what a simulation
//! takes and gives. Nothing here imports the evaluation pipeline, the optimiser, the
//! recorder or the CLI.

mod contact3d;
mod criteria;
mod driver;
mod equilibrium;
mod events;
mod finger;
mod integrate;
mod memory;
mod result;
mod scene;
mod tracking;

pub use contact3d::{closest_segments, quat_matrix, V3};
pub use criteria::{force_margin, impact, impact_limits, r_area, u_min, Impact};
pub use driver::{drive, simulate as simulate_scene, End, Run};
pub use equilibrium::{finger_equilibrium, Equilibrium};
pub use events::{hermite_may_cross, locate, Crossing, EventKind, EventValues};
pub use finger::{ContactState, FingerEval, FingerLinkage, FingerModel, Kink};
pub use integrate::{
    fd_jacobian, hermite, Accepted, Dopri5, Lu, Partition, Piece, Radau5, RadauCoefficients, RadauIIA, Rhs, Scalar,
    Stats, StepError, Stepper, Tol, TrBdf2,
};
pub use memory::{Memory, MemoryChange};
pub use result::{DynOutcome, DynamicsResult, FirstContact, Method, Mode, Sample, SimOptions, Trajectory, MAX_EVENTS};
pub use scene::centred::{
    compliant_equilibrium, simulate_grasp, simulate_grasp_into, simulate_grasp_traj, CentredScene, FingerOde, State,
    EVENTS as CENTRED_EVENTS, NS,
};
pub use scene::free::{
    free_tolerances, simulate_free, FreeEval, FreeJacobian, FreeResult, FreeScene, FreeSetup, PoseSample,
    EF as FREE_EVENTS, NF as FREE_NS,
};
pub use scene::offset::{simulate_offset, OffsetResult, OffsetScene, PairEval, OFFSET_EVENTS};
pub use scene::{Point, Response, Scene};
pub use tracking::Tracker;
