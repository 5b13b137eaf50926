//! The free scene (MODEL.md §14.1–14.4): both fingers close on the object, a free rigid
//! body standing on the ground (z = −h_c) against the palm. Contacts in 3-D: each phalanx
//! capsule against the object's axis segment, the palm capsule, and n_g rim points on the
//! ground, all Hertz–Flores with memory and the 2-D regularised friction of §14.2.
//! State y = (finger 1: q11, q21, q̇11, q̇21 | finger 2 | G (3) | quaternion (w, x, y, z) |
//! v_G (3) | ω (3, world axes)). The run ends at min(t_max, t_obs). The parts (object
//! kinematics, each contact) are in `contacts`; the integrator's Jacobian is computed by
//! blocks (`jacobian`), and its Newton systems eliminate the positions ([`Partition`]).

mod contacts;
mod jacobian;
mod rhs;

pub use jacobian::FreeJacobian;

use super::{End, KeptEval, Response, Run, Scene};
use crate::math::V2;
use crate::model::{Finger, FrictionLaw};
use crate::params::SceneParams;
use crate::sim::contact3d::V3;
use crate::sim::criteria::{impact, Impact};
use crate::sim::driver;
use crate::sim::events::{Crossing, EventKind, EventValues};
use crate::sim::finger::{FingerLinkage, FingerModel};
use crate::sim::integrate::{fd_jacobian, Partition, Piece, Rhs, Stats, StepPoint, Tol};
use crate::sim::memory::{Memory, MemoryChange};
use crate::sim::result::{FreeEnd, PoseSample};
use crate::sim::settings::{Controls, Integration};
use crate::sim::sink::{Point, Sink};
use nalgebra::{Matrix2, SVector, Vector2};

/// State dimension of the free scene.
pub const NF: usize = 21;
/// Most ground points (event slots are fixed at compile time).
pub const NG_MAX: usize = 16;
/// Contacts: 4 phalanges, the palm, the ground points.
pub const NC: usize = 5 + NG_MAX;
/// Contacts whose events fall within this time (s) of a located one change with it.
const SIMULTANEOUS: f64 = 1e-10;
/// Number of event functions of the free scene.
pub const EF: usize = NC + 4;
type St = SVector<f64, NF>;
const G0: usize = 8;
const Q0: usize = 11;
const V0: usize = 15;
const W0: usize = 18;

/// Test and study inputs of the free scene beyond the problem file (MODEL.md §14.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeSetup {
    /// Integrate the fingers (false: they stay open and never touch; the object alone).
    pub fingers: bool,
    /// Initial velocity of G (m/s).
    pub v0: [f64; 3],
    /// Initial tilt about the y axis (rad; the axis leans toward +x), resting on its lowest rim point.
    pub tilt: f64,
    /// A constant force along x through the axis at z = 0 (N).
    pub push_x: f64,
    /// The integrator's Jacobian by dense forward differences (21 evaluations) instead of
    /// by blocks (for comparison).
    pub dense_jacobian: bool,
}

impl Default for FreeSetup {
    fn default() -> Self {
        FreeSetup { fingers: true, v0: [0.0; 3], tilt: 0.0, push_x: 0.0, dense_jacobian: false }
    }
}

/// One contact at a state (world frame).
#[derive(Debug, Clone, Copy, Default)]
pub struct Contact3 {
    /// Penetration δ (m).
    pub delta: f64,
    /// δ̇ (m/s).
    pub delta_dot: f64,
    /// Normal force (N).
    pub normal: f64,
    /// The closest point on the object's axis was clamped to an end (rim or face contact).
    pub rim: bool,
}

/// The free scene's model at one state.
#[derive(Debug, Clone, Copy)]
pub struct FreeEval {
    /// The linkages of finger 1 and 2 (local frames).
    pub f: [FingerLinkage; 2],
    /// Every contact (0–3 phalanges, 4 palm, 5.. ground).
    pub c: [Contact3; NC],
    /// q̈ of both fingers.
    pub qdd: [Vector2<f64>; 2],
    /// dv_G/dt and dω/dt.
    pub acc: (V3, V3),
    /// Tilt acos(a·z) (rad).
    pub tilt: f64,
    /// Translational and rotational kinetic energy of the object (J).
    pub e_obj: (f64, f64),
    /// Total energy: fingers, object, gravity of the object, contact elastic energies (J).
    pub energy: f64,
    /// Smooth piece.
    pub piece: Piece,
    /// Position of G (m).
    pub pos: V3,
    /// Orientation (w, x, y, z).
    pub quat: [f64; 4],
    /// Angular velocity (world, rad/s).
    pub omega: V3,
    /// The axis a (world).
    pub axis: V3,
}

/// The outputs of MODEL.md §14.4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeResult {
    /// Object offset x_off (m).
    pub x_off: f64,
    /// Largest horizontal displacement of G (m).
    pub object_max_displacement: f64,
    /// Largest |Δx| of G (m).
    pub object_max_dx: f64,
    /// Largest |Δy| of G (m).
    pub object_max_dy: f64,
    /// Largest tilt (°).
    pub object_max_tilt_deg: f64,
    /// Largest |a_x|: the axis leaning along the palm, i.e. tilt about y (rad, sine).
    pub object_max_tilt_y: f64,
    /// Largest spin about the vertical, 2|q_z| (rad; small-angle).
    pub object_max_spin: f64,
    /// Horizontal displacement at the end (m).
    pub object_final_displacement: f64,
    /// Tilt at the end (°).
    pub object_final_tilt_deg: f64,
    /// Peak translational kinetic energy during the first contact (J).
    pub object_peak_e_trans: f64,
    /// Peak rotational kinetic energy during the first contact (J).
    pub object_peak_e_rot: f64,
    /// First phalanx contact time (s).
    pub first_contact_t: Option<f64>,
    /// First phalanx: 1 proximal, 2 distal (finger 1 or 2).
    pub first_contact_phalanx: Option<u8>,
    /// The §9.1 energies at the first contact as this scene's fingers hit.
    pub first_impact: Option<Impact>,
    /// The verdict: max displacement > Δx_max or max tilt > θ_max.
    pub moved: bool,
    /// Tilt above 45° at some time.
    pub toppled: bool,
    /// No phalanx in contact at the end.
    pub escaped: bool,
    /// A loaded phalanx met the object's rim or a face.
    pub rim_contact: bool,
    /// How the run ended.
    pub end: FreeEnd,
    /// Time reached (s).
    pub t_end: f64,
    /// Events located.
    pub events: u32,
    /// Integrator counters.
    pub stats: Stats,
    /// Right-hand-side evaluations (including event location).
    pub rhs_evals: u64,
    /// Partial evaluations of the block Jacobian (one per column: a finger and its
    /// contacts, or the contacts alone).
    pub jac_block_evals: u64,
    /// Wall seconds.
    pub cpu_s: f64,
    /// Energy at the start and at the end (J).
    pub energy: [f64; 2],
    /// Largest energy increase between two consecutive accepted states (J; ≈ 0).
    pub max_energy_rise: f64,
}

/// The free scene during a run.
pub struct FreeScene<'a> {
    model: FingerModel<'a>,
    s: &'a SceneParams,
    setup: FreeSetup,
    mem: [Memory; NC],
    ng: usize,
    rim_body: [V3; NG_MAX],
    m: f64,
    j_body: V3,
    chi: f64,
    law_palm: FrictionLaw,
    law_ground: FrictionLaw,
    x_off: f64,
    evals: u64,
    jac_evals: u64,
    accepted: KeptEval<NF, FreeEval>,
    // tracking
    g_start: V3,
    out: FreeResult,
    first_k: Option<usize>,
    first_open: bool,
    last_energy: Option<f64>,
    /// How the run ended, when the scene ended it (else the driver's end says).
    end: Option<FreeEnd>,
}

impl<'a> FreeScene<'a> {
    /// The scene of finger `f` with spring preload `tau_s0` on the object at x_off.
    pub fn new(f: &'a Finger, s: &'a SceneParams, tau_s0: f64, x_off: f64, setup: FreeSetup) -> Self {
        let ng = s.setup.ground_points.min(NG_MAX);
        let mut rim_body = [V3::zeros(); NG_MAX];
        for k in 0..ng {
            // mirror images (x → −x) of each other exactly where the set is symmetric, so a
            // symmetric grasp stays symmetric to rounding
            let m = if ng.is_multiple_of(2) { (ng / 2 + ng - k) % ng } else { k };
            rim_body[k] = if m < k {
                V3::new(-rim_body[m].x, rim_body[m].y, rim_body[m].z)
            } else {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / ng as f64;
                V3::new(s.object.radius * phi.cos(), s.object.radius * phi.sin(), -s.object.length / 2.0)
            };
        }
        let m = s.object.mass();
        let k = &s.contact;
        let out = FreeResult {
            x_off,
            object_max_displacement: 0.0,
            object_max_dx: 0.0,
            object_max_dy: 0.0,
            object_max_tilt_deg: 0.0,
            object_max_tilt_y: 0.0,
            object_max_spin: 0.0,
            object_final_displacement: 0.0,
            object_final_tilt_deg: 0.0,
            object_peak_e_trans: 0.0,
            object_peak_e_rot: 0.0,
            first_contact_t: None,
            first_contact_phalanx: None,
            first_impact: None,
            moved: false,
            toppled: false,
            escaped: false,
            rim_contact: false,
            end: FreeEnd::Stopped,
            t_end: 0.0,
            events: 0,
            stats: Stats::default(),
            rhs_evals: 0,
            jac_block_evals: 0,
            cpu_s: 0.0,
            energy: [f64::NAN; 2],
            max_energy_rise: 0.0,
        };
        FreeScene {
            model: FingerModel::new(f, s, tau_s0),
            s,
            setup,
            mem: [Memory::default(); NC],
            ng,
            rim_body,
            m,
            j_body: V3::new(s.object.inertia(), s.object.inertia(), m * s.object.radius.powi(2) / 2.0),
            chi: k.chi(),
            law_palm: FrictionLaw { mu_s: s.env.mu_p, mu_d: s.env.mu_p, v_s: k.v_s, v_d: k.v_d },
            law_ground: FrictionLaw {
                mu_s: s.env.mu_g,
                mu_d: s.env.mu_g,
                v_s: s.setup.ground_v_s,
                v_d: s.setup.ground_v_d,
            },
            x_off,
            evals: 0,
            jac_evals: 0,
            accepted: KeptEval::default(),
            g_start: V3::zeros(),
            out,
            first_k: None,
            first_open: false,
            last_energy: None,
            end: None,
        }
    }

    /// Pre-sink δ_g0 = (m_c g / (n_g K_g))^{2/3} of §14.1.
    pub fn presink(&self) -> f64 {
        (self.m * self.s.env.g / (self.ng as f64 * self.s.setup.ground_k)).powf(2.0 / 3.0)
    }

    fn note(&mut self, ev: &FreeEval) {
        let o = &mut self.out;
        let dx = ev.pos.x - self.g_start.x;
        let dy = ev.pos.y - self.g_start.y;
        o.object_max_dx = o.object_max_dx.max(dx.abs());
        o.object_max_dy = o.object_max_dy.max(dy.abs());
        o.object_max_displacement = o.object_max_displacement.max(dx.hypot(dy));
        o.object_max_tilt_deg = o.object_max_tilt_deg.max(ev.tilt.to_degrees());
        o.object_max_tilt_y = o.object_max_tilt_y.max(ev.axis.x.abs());
        o.object_max_spin = o.object_max_spin.max(2.0 * ev.quat[3].abs());
        if self.first_open {
            o.object_peak_e_trans = o.object_peak_e_trans.max(ev.e_obj.0);
            o.object_peak_e_rot = o.object_peak_e_rot.max(ev.e_obj.1);
        }
        for k in 0..4 {
            o.rim_contact |= ev.c[k].rim && ev.c[k].normal > 0.0;
        }
        if let Some(e0) = self.last_energy {
            o.max_energy_rise = o.max_energy_rise.max(ev.energy - e0);
        }
        self.last_energy = Some(ev.energy);
    }
}

impl Rhs<NF> for FreeScene<'_> {
    fn eval(&mut self, _t: f64, y: &St) -> Option<St> {
        self.evals += 1;
        Some(self.rhs(y)?.0)
    }
    fn piece(&self, y: &St) -> Piece {
        self.rhs(y).map_or(Piece::UNDEFINED, |r| r.1)
    }
    fn eval_piece(&mut self, _t: f64, y: &St) -> Option<(St, Piece)> {
        self.evals += 1;
        self.rhs(y)
    }
    fn eval_accepted(&mut self, _t: f64, y: &St) -> Option<(St, Piece)> {
        self.evals += 1;
        let ev = self.eval_with(y, true)?;
        let out = (self.deriv(y, &ev), ev.piece);
        self.accepted.keep(y, ev);
        Some(out)
    }
    fn newton_partition(&self) -> Option<Partition<NF>> {
        // the positions: both fingers' angles, G, and the quaternion (its rate depends on
        // itself and ω only)
        (!self.setup.dense_jacobian)
            .then(|| {
                Partition::new(&[&[0], &[1], &[4], &[5], &[G0], &[G0 + 1], &[G0 + 2], &[Q0, Q0 + 1, Q0 + 2, Q0 + 3]])
            })
            .flatten()
    }
    fn jacobian(&mut self, at: &StepPoint<NF>, piece: Piece, jac: &mut FreeJacobian, stats: &mut Stats) -> bool {
        if self.setup.dense_jacobian {
            fd_jacobian(self, at, piece, jac, stats)
        } else {
            self.block_jacobian(&at.y, piece, jac)
        }
    }
}

const fn free_events() -> [EventKind; EF] {
    let mut e = [EventKind::Stability; EF];
    let mut k = 0;
    while k < NC {
        e[k] = EventKind::Contact(k as u8);
        k += 1;
    }
    e[NC] = EventKind::Singular(0);
    e[NC + 1] = EventKind::Singular(1);
    e[NC + 2] = EventKind::Stop(0);
    e[NC + 3] = EventKind::Stop(1);
    e
}

/// The free scene's event kinds, built once.
const FREE_EVENT_KINDS: [EventKind; EF] = free_events();

impl Scene<NF, EF> for FreeScene<'_> {
    type Eval = FreeEval;

    fn events(&self) -> [EventKind; EF] {
        FREE_EVENT_KINDS
    }
    fn initial_state(&self) -> St {
        let s = self.s;
        let o = &self.model.finger.open;
        let (r, lc, hc) = (s.object.radius, s.object.length, s.object.grasp_height);
        let th = self.setup.tilt;
        let mut y = St::zeros();
        y.fixed_rows_mut::<4>(0).copy_from(&nalgebra::Vector4::new(o.q11, o.q21, 0.0, 0.0));
        y.fixed_rows_mut::<4>(4).copy_from(&nalgebra::Vector4::new(o.q11, o.q21, 0.0, 0.0));
        let gz = if th == 0.0 { lc / 2.0 - hc - self.presink() } else { -hc + r * th.sin() + (lc / 2.0) * th.cos() };
        y[G0] = self.x_off;
        y[G0 + 1] = r;
        y[G0 + 2] = gz;
        y[Q0] = (th / 2.0).cos();
        y[Q0 + 2] = (th / 2.0).sin();
        for j in 0..3 {
            y[V0 + j] = self.setup.v0[j];
        }
        y
    }
    fn evaluate(&self, y: &St) -> Option<FreeEval> {
        self.eval_with(y, true)
    }
    fn take_accepted(&mut self, y: &St) -> Option<FreeEval> {
        self.accepted.take(y)
    }
    fn derivative(&self, y: &St, ev: &FreeEval) -> St {
        self.deriv(y, ev)
    }
    fn event_values(&self, _y: &St, ev: &FreeEval) -> EventValues<EF> {
        let eps = self.s.contact.eps_sep;
        let mut g = [0.0; EF];
        let mut rate = [0.0; EF];
        for k in 0..NC {
            g[k] = self.mem[k].event_value(ev.c[k].delta, eps);
            rate[k] = ev.c[k].delta_dot;
        }
        let fingers = if self.setup.fingers { 1.0 } else { f64::NAN };
        g[NC] = (ev.f[0].sin_q13().abs() - 1e-3) * fingers;
        g[NC + 1] = (ev.f[1].sin_q13().abs() - 1e-3) * fingers;
        g[NC + 2] = ev.f[0].theta2 * fingers;
        g[NC + 3] = ev.f[1].theta2 * fingers;
        rate[NC + 2] = ev.f[0].theta2_dot;
        rate[NC + 3] = ev.f[1].theta2_dot;
        EventValues { g, rate }
    }
    fn event_value(&self, i: usize, y: &St) -> Option<f64> {
        self.event_value_at(i, y)
    }
    fn crossing(&self, i: usize) -> Option<Crossing> {
        let kind = FREE_EVENT_KINDS[i];
        match kind {
            EventKind::Contact(c) if (c as usize) >= 5 + self.ng => None,
            EventKind::Contact(c) if (c as usize) < 4 && !self.setup.fingers => None,
            EventKind::Singular(_) | EventKind::Stop(_) if !self.setup.fingers => None,
            EventKind::Contact(c) => Some(kind.crossing(self.mem[c as usize].active)),
            _ => Some(kind.crossing(false)),
        }
    }
    fn begin(&mut self, y: &St, ev: &FreeEval, _g: &EventValues<EF>) -> bool {
        self.g_start = V3::new(y[G0], y[G0 + 1], y[G0 + 2]);
        // ground points pre-sunk at rest: in contact from the start
        for k in 5..5 + self.ng {
            if ev.c[k].delta > 0.0 {
                self.mem[k] = Memory { active: true, vminus: self.s.contact.v_min };
            }
        }
        if (0..5).any(|k| ev.c[k].delta > 1e-12) {
            self.end = Some(FreeEnd::InitialPenetration);
            return false;
        }
        let ev1 = self.eval_with(y, true);
        if let Some(e) = ev1 {
            self.out.energy[0] = e.energy;
            self.note(&e);
        }
        true
    }
    fn handle(&mut self, i: usize, t: f64, ev: &FreeEval, _end: &EventValues<EF>) -> Response {
        let s = self.s;
        match FREE_EVENT_KINDS[i] {
            EventKind::Contact(_) => {
                for k in 0..5 + self.ng {
                    let c = &ev.c[k];
                    let mut ch = self.mem[k].update(c.delta, c.delta_dot, k == i, s.contact.eps_sep, s.contact.v_min);
                    if ch == MemoryChange::Unchanged && k != i && self.crossing(k).is_some() {
                        // a contact that crosses within SIMULTANEOUS of this one (the mirror
                        // image of a symmetric pair, off by rounding) changes here too,
                        // instead of as an event of its own an instant later
                        let g = self.mem[k].event_value(c.delta, s.contact.eps_sep);
                        let ahead = g + SIMULTANEOUS * c.delta_dot;
                        if !self.mem[k].active && g <= 0.0 && ahead > 0.0 {
                            self.mem[k] = Memory { active: true, vminus: c.delta_dot.max(s.contact.v_min) };
                            ch = MemoryChange::Onset;
                        } else if self.mem[k].active && g > 0.0 && ahead <= 0.0 {
                            self.mem[k] = Memory::default();
                            ch = MemoryChange::Separation;
                        }
                    }
                    if k < 4 && ch == MemoryChange::Onset && self.first_k.is_none() {
                        let fe = &ev.f[k / 2];
                        let minv = fe.m.try_inverse().unwrap_or(Matrix2::zeros());
                        let p = fe.pose;
                        let f = self.model.finger;
                        // contact row in the plane: δ̇ = a q̇ with a = J_Pᵀ n (n: in-plane normal)
                        let geo = self
                            .model
                            .geometry(&p, V2::new(if k / 2 == 0 { self.x_off } else { -self.x_off }, s.object.radius));
                        let g = geo[k % 2];
                        let jp = fe.kin.point_jacobian(f, &p, g.point, k % 2 == 1);
                        let row = jp.transpose() * g.normal;
                        let mf = 1.0 / row.dot(&(minv * row));
                        self.first_k = Some(k);
                        self.first_open = true;
                        self.out.first_contact_t = Some(t);
                        self.out.first_contact_phalanx = Some((k % 2) as u8 + 1);
                        self.out.first_impact = Some(impact(s, mf, c.delta_dot));
                    } else if Some(k) == self.first_k && ch == MemoryChange::Separation {
                        self.first_open = false;
                    }
                }
                Response { restart: true, stop: false }
            }
            EventKind::Singular(_) => {
                self.end = Some(FreeEnd::Singular);
                Response { restart: false, stop: true }
            }
            _ => Response { restart: true, stop: false },
        }
    }
    fn track(&mut self, _at: Point, ev: &FreeEval, _g: &EventValues<EF>) {
        self.note(ev);
    }
    fn memories(&self) -> &[Memory] {
        &self.mem
    }
    fn sample<K: Sink + ?Sized>(&self, at: Point, t: f64, y: &St, ev: &FreeEval, sink: &mut K) {
        let pose = PoseSample {
            t,
            g: [y[G0], y[G0 + 1], y[G0 + 2]],
            q: ev.quat,
            tilt: ev.tilt,
            fingers: [y[0], y[1], y[4], y[5]],
            energy: ev.energy,
            delta: std::array::from_fn(|k| ev.c[k].delta),
            normal: std::array::from_fn(|k| ev.c[k].normal),
        };
        sink.pose(at, &pose);
    }
}

impl FreeScene<'_> {
    /// The output of a finished run: the criteria's verdicts and the measured values.
    fn finish(self, run: &Run<NF, FreeEval>) -> FreeResult {
        let mut o = self.out;
        o.end = self.end.unwrap_or(match run.end {
            End::TimeUp => FreeEnd::Observed,
            End::StepBudget => FreeEnd::StepBudget,
            End::StepTooSmall => FreeEnd::StepTooSmall,
            End::Undefined => FreeEnd::NotMountable,
            End::Aborted => FreeEnd::TooManyEvents,
            End::Stopped | End::Declined => FreeEnd::Stopped,
        });
        o.t_end = run.t;
        o.events = run.events;
        o.stats = run.stats;
        o.rhs_evals = self.evals + run.locate_evals;
        o.jac_block_evals = self.jac_evals;
        if let Some(ev) = &run.last {
            o.object_final_tilt_deg = ev.tilt.to_degrees();
            o.object_final_displacement = (ev.pos.x - self.g_start.x).hypot(ev.pos.y - self.g_start.y);
            o.escaped = self.setup.fingers && (0..4).all(|k| ev.c[k].normal <= 0.0);
            o.energy[1] = ev.energy;
        }
        o.toppled = o.object_max_tilt_deg > 45.0;
        let crit = &self.s.criteria;
        o.moved = o.object_max_displacement > crit.dx_max || o.object_max_tilt_deg > crit.theta_max.to_degrees();
        o
    }
}

/// Tolerances of the free scene: fingers as the centred scene, the object's position and
/// orientation at atol·1e-1 m (the ground's pre-sink is ≈ 1 µm), velocities at atol; the
/// fingers' and the object's rates' absolute tolerances times the factors of `integ.scaling`.
pub fn free_tolerances(integ: &Integration) -> Tol<NF> {
    let sc = integ.scaling;
    let mut atol = St::repeat(integ.atol);
    for a in atol.iter_mut().take(G0) {
        *a *= sc.free_fingers_atol;
    }
    for j in 0..7 {
        atol[G0 + j] = integ.atol * 0.1;
    }
    for a in atol.iter_mut().skip(V0) {
        *a *= sc.free_object_rates_atol;
    }
    Tol { rtol: integ.rtol, atol }
}

/// Simulate the free scene of finger `f` (spring preload `tau_s0`) with the object at
/// `x_off`, from t = 0 to min(t_max, t_obs) (`t_end` overrides it when given), reporting
/// the poses to `sink`.
#[allow(clippy::too_many_arguments)]
// not inlined: its own symbol for `make bench-instructions`' inclusive count
#[inline(never)]
pub(crate) fn run<K: Sink + ?Sized>(
    f: &Finger,
    s: &SceneParams,
    tau_s0: f64,
    x_off: f64,
    setup: FreeSetup,
    t_end: Option<f64>,
    integ: &Integration,
    sink: &mut K,
) -> FreeResult {
    let mut scene = FreeScene::new(f, s, tau_s0, x_off, setup);
    let t_end = t_end.unwrap_or(s.criteria.t_max.min(s.setup.t_obs));
    // the free scene has no pipeline mode: it always runs to t_end
    let run = driver::simulate(&mut scene, integ, &Controls::DIAGNOSTIC, free_tolerances(integ), t_end, sink);
    scene.finish(&run)
}
