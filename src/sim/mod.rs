//! Simulation (MODEL.md §8–9): integrators, events, the generic step loop, scenes, the
//! finger model, contact memory, criteria.
//!
//! Layout (private modules, re-exported flat): `integrate/` (one file per method, LU,
//! finite-difference Jacobian, block elimination of Newton matrices, Hermite dense output)
//! → `events` (kinds, crossing rules, root locator, the search for a step's earliest
//! event) → `scene/` (the [`Scene`] trait and what is integrated: the centred, offset and
//! free scenes, `contact3d` the free scene's 3-D contacts) built from `finger` (one finger
//! against a given object), `memory` (the contact-memory rule), `tracking` (the criteria
//! the grasp scenes share), `equilibrium` (§8.9) and `criteria` (§9) → `driver` (the step
//! loop, generic over a scene) → `simulate` (the one entry: a finger in a [`SceneSpec`]).
//! `settings` holds the numerics and run controls, `sink` where samples and events go,
//! `result` what a simulation gives, `columns` the names of a trajectory's values. Nothing here imports the evaluation pipeline, the
//! optimiser, the recorder or the CLI.

mod columns;
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
mod settings;
mod simulate;
mod sink;
mod tracking;

pub use columns::{
    finger_from_values, finger_values, pose_values, sample_from_values, sample_series_fields, sample_values,
    series_field, trajectory_columns, trajectory_row, Column, FingerColumn, PoseColumn, SceneColumn, FINGER2_COLUMNS,
    FINGER_COLUMNS, HAND_COLUMNS, POSE_COLUMNS, POSE_TABLE, SAMPLE_COLUMNS, TIME,
};
pub use contact3d::{closest_segments, quat_matrix, V3};
pub use criteria::{force_margin, impact, impact_limits, r_area, u_min, Impact};
pub use driver::drive;
pub use equilibrium::{finger_equilibrium, Equilibrium};
pub use events::{hermite_may_cross, locate, Crossing, EventKind, EventSearch, EventValues};
pub use finger::{ContactState, FingerEval, FingerLinkage, FingerModel, Kink};
pub use integrate::{
    fd_jacobian, hermite, Dopri5, Lu, Partition, Piece, Radau5, Radau5Scheme, RadauCoefficients, RadauIIA,
    RadauIIAScheme, RadauScheme, RadauStepper, Rhs, Scalar, Stats, StepError, StepPoint, Stepper, Tol, TrBdf2,
};
pub use memory::{Memory, MemoryChange};
pub use result::{
    DynOutcome, DynamicsResult, FingerSample, FirstContact, FreeEnd, PoseSample, Sample, Trajectory, MAX_EVENTS,
};
pub use scene::centred::{
    compliant_equilibrium, tolerances as centred_tolerances, CentredScene, FingerOde, State, EVENTS as CENTRED_EVENTS,
    NS,
};
pub use scene::free::{
    free_tolerances, FreeEval, FreeJacobian, FreeResult, FreeScene, FreeSetup, EF as FREE_EVENTS, NF as FREE_NS,
};
pub use scene::offset::{OffsetResult, OffsetScene, PairEval, StartFailure, OFFSET_EVENTS};
pub use scene::{End, Response, Run, Scene};
pub use settings::{
    revision_of, Controls, Integration, Method, Mode, Scaling, ACROSS_REVISIONS_RTOL, DEFAULT_AUTO_REVISION,
    SIMULATOR_REVISION,
};
pub use simulate::{diagnostic_grasp, simulate, SceneResult, SceneSpec};
pub use sink::{EventNote, Point, Sink};
pub use tracking::{EndValues, GraspLimits, Tracker};
