//! Parameters: the problem file turned into typed values — the scene constants by section
//! ([`Hand`], [`Object`], [`ContactLaw`], [`Environment`], [`Criteria`]), the solver
//! settings (with the integration [`Method`]), the nominal [`Design`] and the [`Bounds`].
//! The lowest layer: it depends on nothing of gripopt but `math`, `error` and `fsutil`.

mod checker;
mod design;
mod limits;
mod load;
mod method;
mod robust;
mod robust_load;
mod scene;
mod scene_kind;
mod uncertainty;

pub use design::{Bounds, Design, DesignParameters, DESIGN_NAMES};
pub use limits::num as fmt_num;
pub use limits::{limit, Limit, LIMITS, MAX_FILE_BYTES, MAX_R_SING};
pub use load::{Problem, SolverSettings};
pub use method::Method;
pub use robust::{
    corner_count, describe, Aggregation, Certify, Robust, Sampling, Scenario, STREAM_CERTIFY, STREAM_OPTIMISE,
    STREAM_VERIFY,
};
pub use scene::{ContactLaw, Criteria, Environment, ForceModel, Hand, Object, ObjectCase, SceneParams};
pub use scene_kind::{scene_kinds_using, SceneChoice, SceneKind, SceneSetup};
pub use uncertainty::{input_slot, phi, phi_inv, Dist, InputRow, Uncertainty, INPUTS, N_INPUTS};
