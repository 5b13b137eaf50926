//! The MuJoCo model (MJCF) of an exported design: both five-bar fingers as kinematic trees
//! closed by `connect` equality constraints, the palm, the object (fixed or free), the
//! motor and spring torques as actuators, the distal stop as a joint limit, the contact
//! pairs, and every MODEL.md quantity named in a comment (docs/export.md).
//!
//! World frame = the hand frame of MODEL.md §2 with z up (§14.1): the hand plane is z = 0,
//! the palm surface the line y = 0, the ground the plane z = −h_c. Finger 1 is built in the
//! world frame; finger 2 is the same tree inside a frame turned by π about y, which is
//! exactly the mirror x → −x of the planar linkage (every part is symmetric about z = 0).
//! Every hinge's `ref` is its open-pose angle, so `qpos` holds MODEL.md's joint angles
//! (q11, q12, q21, q22; finger 2's in its local, mirrored frame) and qpos0 is the open pose.

use super::xml::XmlWriter;
use super::{num, ExportedDesign, ObjectMode};
use crate::math::{e, V2};
use std::f64::consts::PI;

/// MuJoCo's solver and contact settings written into the file (docs/export.md says why).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MujocoSettings {
    /// Time step (s).
    pub timestep: f64,
    /// Integrator (`RK4`: the loop closure and the first contact to 1e-5, docs/export.md).
    pub integrator: &'static str,
    /// Object contacts' solref (time constant s, damping ratio): chosen for the restitution e.
    pub contact_solref: [f64; 2],
    /// Object contacts' solimp (dmin, dmax, width m, midpoint, power).
    pub contact_solimp: [f64; 5],
    /// Ratio of frictional to normal constraint impedance.
    pub impratio: f64,
    /// Loop-closure constraints' solref (the stiffest MuJoCo allows: 2 time steps, critical).
    pub loop_solref: [f64; 2],
    /// Loop-closure constraints' solimp (impedance 0.9999, MuJoCo's largest).
    pub loop_solimp: [f64; 5],
    /// Distal stop (joint limit) solref: MuJoCo's approximation of the Hunt–Crossley stop.
    pub stop_solref: [f64; 2],
    /// Distal stop solimp.
    pub stop_solimp: [f64; 5],
}

/// The settings every export uses (docs/export.md: how they were chosen and measured).
pub const MUJOCO: MujocoSettings = MujocoSettings {
    timestep: 1e-5,
    integrator: "RK4",
    contact_solref: [1e-4, 0.48],
    contact_solimp: [0.99, 0.99, 1e-3, 0.5, 2.0],
    impratio: 1.0,
    loop_solref: [2e-5, 1.0],
    loop_solimp: [0.9999, 0.9999, 1e-3, 0.5, 2.0],
    stop_solref: [2e-4, 1.0],
    stop_solimp: [0.99, 0.99, 1e-3, 0.5, 2.0],
};

fn list(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ")
}

/// One empty element `tag` per finger, its attributes made from the finger's name prefix
/// (`f1`, `f2`).
fn each_finger(xml: &mut XmlWriter, tag: &str, attrs: impl Fn(&str) -> Vec<(&'static str, String)>) {
    for pre in ["f1", "f2"] {
        xml.empty(tag, &attrs(pre));
    }
}

fn a(k: &'static str, v: impl Into<String>) -> (&'static str, String) {
    (k, v.into())
}

fn deg(x: f64) -> String {
    format!("{:.9}°", x.to_degrees())
}

/// Inertia tensor (about the COM, body axes) of a rod of mass m, length ℓ, radius w along
/// the unit vector u in the plane z = 0: (xx, yy, zz, xy, xz, yz).
fn rod_tensor(m: f64, l: f64, w: f64, u: V2) -> [f64; 6] {
    let axial = m * w * w / 2.0;
    let trans = m * (3.0 * w * w + l * l) / 12.0;
    // trans (I − u uᵀ) + axial u uᵀ, with u_z = 0
    [
        trans + (axial - trans) * u.x * u.x,
        trans + (axial - trans) * u.y * u.y,
        trans,
        (axial - trans) * u.x * u.y,
        0.0,
        0.0,
    ]
}

/// Add the parallel-axis term m (|d|² I − d dᵀ) for an offset d in the plane.
fn shifted(t: [f64; 6], m: f64, d: V2) -> [f64; 6] {
    [t[0] + m * d.y * d.y, t[1] + m * d.x * d.x, t[2] + m * d.norm_squared(), t[3] - m * d.x * d.y, t[4], t[5]]
}

/// Body 22 (link 22 along x, distal phalanx at ψ): mass, COM and inertia about the COM.
fn body22_inertia(x: &ExportedDesign) -> (f64, V2, [f64; 6]) {
    let f = &x.finger;
    let w = f.w;
    let lam = x.scene.hand.rho_f * PI * w * w;
    let (ma, mb) = (lam * f.l22, lam * f.t22);
    let u = e(f.psi);
    let (ca, cb) = (V2::new(f.l22 / 2.0, 0.0), u * (f.t22 / 2.0));
    let s = f.mass.s22;
    let ta = shifted(rod_tensor(ma, f.l22, w, V2::new(1.0, 0.0)), ma, ca - s);
    let tb = shifted(rod_tensor(mb, f.t22, w, u), mb, cb - s);
    let mut t = [0.0; 6];
    for k in 0..6 {
        t[k] = ta[k] + tb[k];
    }
    (f.mass.m[3], s, t)
}

fn rod_inertial(xml: &mut XmlWriter, m: f64, l: f64, w: f64) {
    let t = rod_tensor(m, l, w, V2::new(1.0, 0.0));
    xml.empty("inertial", &[a("pos", list(&[l / 2.0, 0.0, 0.0])), a("mass", num(m)), a("diaginertia", list(&t[..3]))]);
}

/// Hinge about the body's z axis with the open-pose angle as `ref`.
fn hinge(xml: &mut XmlWriter, name: &str, q0: f64, extra: &[(&'static str, String)]) {
    let mut at = vec![a("name", name), a("type", "hinge"), a("axis", "0 0 1"), a("ref", num(q0))];
    at.extend_from_slice(extra);
    xml.empty("joint", &at);
}

fn capsule(xml: &mut XmlWriter, name: &str, to: V2, w: f64, class: &str) {
    xml.empty(
        "geom",
        &[
            a("name", name),
            a("class", class),
            a("type", "capsule"),
            a("fromto", list(&[0.0, 0.0, 0.0, to.x, to.y, 0.0])),
            a("size", num(w)),
        ],
    );
}

fn site(xml: &mut XmlWriter, name: &str, p: V2) {
    xml.empty("site", &[a("name", name), a("pos", list(&[p.x, p.y, 0.0]))]);
}

/// One finger's two chains (in the current frame: the world for finger 1, the mirror frame
/// for finger 2), with joint names `{pre}_q11` …
fn finger(xml: &mut XmlWriter, x: &ExportedDesign, set: &MujocoSettings, pre: &str) {
    let f = &x.finger;
    let (w, o, m, i) = (f.w, f.open, f.mass.m, f.mass.i);
    let b2 = f.o21.x;
    let rot = |q: f64| list(&[0.0, 0.0, 1.0, q]);
    xml.comment(&format!(
        "chain 1 (MODEL.md §8.1): link 11, actuated, from O11 = (b/2, 0) = ({}, 0) m, length l11 = p·l21 = {} m",
        num(b2),
        num(f.l11)
    ));
    xml.open(
        "body",
        &[a("name", format!("{pre}_link11")), a("pos", list(&[b2, 0.0, 0.0])), a("axisangle", rot(o.q11))],
    );
    xml.comment(&format!("q11: absolute angle of link 11; open pose q11_0 = {} rad ({})", num(o.q11), deg(o.q11)));
    hinge(xml, &format!("{pre}_q11"), o.q11, &[]);
    xml.comment(&format!(
        "m11 = λ·l11 = {} kg (λ = ρ_f π w²), I11 = m11 (w²/4 + l11²/3) = {} kg·m² about O11 (§4)",
        num(m[0]),
        num(i[0])
    ));
    rod_inertial(xml, m[0], f.l11, w);
    capsule(xml, &format!("{pre}_link11_rod"), V2::new(f.l11, 0.0), w, "link");
    site(xml, &format!("{pre}_O12"), V2::new(f.l11, 0.0));
    xml.comment(&format!(
        "link 12, the transmission bar O12 → O13, length l12 = |O13_0 − O12_0| = {} m (§3.3)",
        num(f.l12)
    ));
    xml.open(
        "body",
        &[a("name", format!("{pre}_link12")), a("pos", list(&[f.l11, 0.0, 0.0])), a("axisangle", rot(o.q12))],
    );
    xml.comment(&format!("q12: angle from x11 to x12; open pose q12_0 = {} rad ({})", num(o.q12), deg(o.q12)));
    hinge(xml, &format!("{pre}_q12"), o.q12, &[]);
    xml.comment(&format!("m12 = λ·l12 = {} kg, I12 = {} kg·m² about O12 (§4)", num(m[1]), num(i[1])));
    rod_inertial(xml, m[1], f.l12, w);
    capsule(xml, &format!("{pre}_link12_rod"), V2::new(f.l12, 0.0), w, "link");
    site(xml, &format!("{pre}_O13_bar"), V2::new(f.l12, 0.0));
    xml.close();
    xml.close();

    xml.comment(&format!("chain 2: link 21 = the proximal phalanx from O21 = O11 (D3), length l21 = {} m", num(f.l21)));
    xml.open(
        "body",
        &[a("name", format!("{pre}_link21")), a("pos", list(&[b2, 0.0, 0.0])), a("axisangle", rot(o.q21))],
    );
    xml.comment(&format!(
        "q21 = θ1: absolute angle of the proximal phalanx; open pose q21_0 = {} rad ({}, §3.2)",
        num(o.q21),
        deg(o.q21)
    ));
    hinge(xml, &format!("{pre}_q21"), o.q21, &[]);
    xml.comment(&format!("m21 = λ·l21 = {} kg, I21 = {} kg·m² about O21 (§4)", num(m[2]), num(i[2])));
    rod_inertial(xml, m[2], f.l21, w);
    xml.comment("the proximal phalanx: a capsule of radius w on [O21, O22] (§8.5, D11)");
    capsule(xml, &format!("{pre}_proximal"), V2::new(f.l21, 0.0), w, "phalanx");
    site(xml, &format!("{pre}_O22"), V2::new(f.l21, 0.0));
    xml.comment(&format!(
        "body 22 = link 22 (O22 → O13, l22 = r·l11 = {} m) + the distal phalanx (length t22 = {} m at ψ = {} rad = {} from x22)",
        num(f.l22),
        num(f.t22),
        num(f.psi),
        deg(f.psi)
    ));
    xml.open(
        "body",
        &[a("name", format!("{pre}_body22")), a("pos", list(&[f.l21, 0.0, 0.0])), a("axisangle", rot(o.q22))],
    );
    xml.comment(
        "q22: angle from x21 to x22, θ2 = q22 + ψ; open pose q22_0 = −ψ (θ2 = 0, the finger straight on its stop)",
    );
    xml.comment(&format!(
        "distal stop θ2 ≥ 0 (§8.4) as the joint's lower limit q22 = −ψ: MuJoCo's soft limit (solreflimit {}) \
         approximates the Hunt–Crossley law τ_stop = K_stop φ (1 + c_stop φ̇), φ = −θ2, K_stop = {} N·m/rad, \
         c_stop = {} s/rad (custom numerics gripopt_k_stop, gripopt_c_stop; docs/export.md)",
        list(&set.stop_solref),
        num(x.scene.hand.k_stop),
        num(x.scene.hand.c_stop)
    ));
    hinge(
        xml,
        &format!("{pre}_q22"),
        o.q22,
        &[
            a("range", list(&[-f.psi, PI])),
            a("solreflimit", list(&set.stop_solref)),
            a("solimplimit", list(&set.stop_solimp)),
        ],
    );
    let (m22, s22, t22) = body22_inertia(x);
    xml.comment(&format!(
        "m22 = λ (l22 + t22) = {} kg, COM (x_S22, y_S22) = ({}, {}) m, I22 = {} kg·m² about O22 (§4)",
        num(m22),
        num(s22.x),
        num(s22.y),
        num(i[3])
    ));
    xml.empty("inertial", &[a("pos", list(&[s22.x, s22.y, 0.0])), a("mass", num(m22)), a("fullinertia", list(&t22))]);
    capsule(xml, &format!("{pre}_link22_rod"), V2::new(f.l22, 0.0), w, "link");
    xml.comment("the distal phalanx: a capsule of radius w on [O22, tip], tip = O22 + t22 x_d (§8.5)");
    capsule(xml, &format!("{pre}_distal"), e(f.psi) * f.t22, w, "phalanx");
    site(xml, &format!("{pre}_O13"), V2::new(f.l22, 0.0));
    site(xml, &format!("{pre}_tip"), e(f.psi) * f.t22);
    xml.close();
    xml.close();
}

/// The MJCF text of design `x` with MuJoCo settings `set`.
pub fn mjcf(x: &ExportedDesign, set: &MujocoSettings) -> String {
    let s = &x.scene;
    let f = &x.finger;
    let (r, lc, hc) = (s.object.radius, s.object.length, s.object.grasp_height);
    let free = x.placement.object == ObjectMode::Free;
    let mut xml = XmlWriter::new();
    header(&mut xml, x);
    xml.open("mujoco", &[a("model", format!("gripopt {}", x.placement.name()))]);
    xml.comment("SI units; angles in radians");
    xml.empty("compiler", &[a("angle", "radian"), a("autolimits", "true")]);
    xml.comment(&format!(
        "{} with a {} s step: the loop closures hold to < 1e-9 m and the first contact time matches gripopt's to 1e-5 \
         (docs/export.md); gravity g = {} m/s², its in-plane part g_eq = {} m/s² at θ_g = {} rad (§1.1, §8.3; 0: the \
         hand plane is horizontal, §14.1) and the rest along −z",
        set.integrator,
        num(set.timestep),
        num(s.env.g),
        num(s.env.g_eq),
        num(s.env.theta_g)
    ));
    xml.empty(
        "option",
        &[
            a("timestep", num(set.timestep)),
            a("integrator", set.integrator),
            a("gravity", list(&gravity(x))),
            a("cone", "elliptic"),
            a("impratio", num(set.impratio)),
            a("solver", "Newton"),
            a("iterations", "100"),
            a("tolerance", "1e-12"),
        ],
    );
    custom(&mut xml, x);
    defaults(&mut xml);
    visual(&mut xml);
    xml.open("worldbody", &[]);
    xml.empty("light", &[a("pos", "0 0.05 0.6"), a("dir", "0 0 -1"), a("directional", "true")]);
    xml.empty("camera", &[a("name", "top"), a("pos", list(&[0.0, 0.04, 0.45])), a("xyaxes", "1 0 0 0 1 0")]);
    xml.empty("camera", &[a("name", "side"), a("pos", list(&[0.0, -0.45, 0.12])), a("xyaxes", "1 0 0 0 0.26 0.97")]);
    xml.comment(&format!("the ground: the plane z = −h_c = {} m (§14.1)", num(-hc)));
    xml.empty(
        "geom",
        &[
            a("name", "ground"),
            a("type", "plane"),
            a("pos", list(&[0.0, 0.0, -hc])),
            a("size", "0.3 0.3 0.01"),
            a("material", "ground"),
        ],
    );
    xml.comment(&format!(
        "the palm: a fixed capsule of radius w = {} m on (−b/2, −w, 0)–(b/2, −w, 0); its surface is the line y = 0 (§14.2)",
        num(f.w)
    ));
    let b2 = f.o21.x;
    xml.empty(
        "geom",
        &[
            a("name", "palm"),
            a("class", "link"),
            a("type", "capsule"),
            a("fromto", list(&[-b2, -f.w, 0.0, b2, -f.w, 0.0])),
            a("size", num(f.w)),
        ],
    );
    xml.blank();
    xml.comment("finger 1 (x > 0), MODEL.md §2: its local frame is the world frame");
    finger(&mut xml, x, set, "f1");
    xml.blank();
    xml.comment("finger 2: the mirror of finger 1 through x = 0 — the same tree in a frame turned by π about y");
    xml.comment("(its hinges turn about −z, so its joint angles are MODEL.md's local angles, positive when closing)");
    xml.open("body", &[a("name", "f2_mirror"), a("quat", "0 0 1 0")]);
    finger(&mut xml, x, set, "f2");
    xml.close();
    xml.blank();
    object(&mut xml, x, free);
    xml.close();
    loops(&mut xml, x, set);
    contacts(&mut xml, x, set, free);
    actuators(&mut xml, x);
    keyframe(&mut xml, x, free, r, lc, hc);
    xml.close();
    xml.finish()
}

/// Gravity in the world frame: the in-plane part g_eq e(θ_g) (MODEL.md §8.3) and the rest
/// along −z.
fn gravity(x: &ExportedDesign) -> [f64; 3] {
    let env = &x.scene.env;
    let g_in = e(env.theta_g) * env.g_eq;
    if env.g_eq == 0.0 {
        return [0.0, 0.0, -env.g];
    }
    [g_in.x, g_in.y, -(env.g * env.g - env.g_eq * env.g_eq).max(0.0).sqrt()]
}

fn header(xml: &mut XmlWriter, x: &ExportedDesign) {
    let d = &x.design;
    xml.comment(&format!(
        "gripopt {} export: MuJoCo model (MJCF) of a two-finger five-bar gripper and its object\n\
         source: {}\n\
         design (MODEL.md §1.2): l21 = {} m, b = {} m, t22 = {} m, r = {}, p = {}, ψ = {} rad ({})\n\
         scene: {}; stages 0-2: {}\n\
         The model follows MODEL.md (§2 frames, §3 geometry, §4 masses, §6.2 spring, §8.4 stop, §8.5-8.6 contacts,\n\
         §14 free scene); what is exact and what is approximate is in gripopt's docs/export.md.\n\
         Start the grasp from the keyframe `grasp` (the open pose with the motor torque τ applied).",
        env!("CARGO_PKG_VERSION"),
        x.source,
        num(d.l21),
        num(d.b),
        num(d.t22),
        num(d.r),
        num(d.p),
        num(d.psi),
        deg(d.psi),
        x.placement.name(),
        x.statics_discard.as_deref().unwrap_or("passes")
    ));
}

fn custom(xml: &mut XmlWriter, x: &ExportedDesign) {
    let s = &x.scene;
    xml.comment("MODEL.md quantities that MuJoCo's elements cannot hold exactly, for scripts (docs/export.md)");
    xml.open("custom", &[]);
    let items: [(&str, f64); 18] = [
        ("gripopt_tau", s.hand.tau),
        ("gripopt_tau_s0", x.tau_s0),
        ("gripopt_k_s", s.hand.k_s),
        ("gripopt_k_stop", s.hand.k_stop),
        ("gripopt_c_stop", s.hand.c_stop),
        ("gripopt_psi", x.finger.psi),
        ("gripopt_w", x.finger.w),
        ("gripopt_mu_s", s.contact.mu_s),
        ("gripopt_mu_d", s.contact.mu_d),
        ("gripopt_v_s", s.contact.v_s),
        ("gripopt_v_d", s.contact.v_d),
        ("gripopt_restitution", s.contact.restitution),
        ("gripopt_k_contact", s.contact.k_contact),
        ("gripopt_radius", s.object.radius),
        ("gripopt_length", s.object.length),
        ("gripopt_grasp_height", s.object.grasp_height),
        ("gripopt_x_off", x.placement.x_off),
        ("gripopt_free", if x.placement.object == ObjectMode::Free { 1.0 } else { 0.0 }),
    ];
    for (name, v) in items {
        xml.empty("numeric", &[a("name", name), a("data", num(v))]);
    }
    xml.close();
}

fn defaults(xml: &mut XmlWriter) {
    xml.open("default", &[]);
    xml.comment("no joint damping, friction or armature: the linkage of MODEL.md §8 is ideal");
    xml.empty("joint", &[a("damping", "0"), a("armature", "0"), a("frictionloss", "0")]);
    xml.comment("contacts only through the explicit pairs of <contact> (MODEL.md models no others)");
    xml.empty("geom", &[a("contype", "0"), a("conaffinity", "0")]);
    xml.open("default", &[a("class", "link")]);
    xml.empty("geom", &[a("rgba", "0.55 0.57 0.62 1")]);
    xml.close();
    xml.open("default", &[a("class", "phalanx")]);
    xml.empty("geom", &[a("rgba", "0.85 0.45 0.2 1")]);
    xml.close();
    xml.open("default", &[a("class", "object")]);
    xml.empty("geom", &[a("rgba", "0.3 0.55 0.85 0.6")]);
    xml.close();
    xml.close();
}

fn visual(xml: &mut XmlWriter) {
    xml.open("asset", &[]);
    xml.empty(
        "texture",
        &[
            a("name", "grid"),
            a("type", "2d"),
            a("builtin", "checker"),
            a("width", "256"),
            a("height", "256"),
            a("rgb1", "0.9 0.9 0.9"),
            a("rgb2", "0.8 0.8 0.8"),
        ],
    );
    xml.empty("material", &[a("name", "ground"), a("texture", "grid"), a("texrepeat", "20 20")]);
    xml.close();
}

fn object(xml: &mut XmlWriter, x: &ExportedDesign, free: bool) {
    let o = &x.scene.object;
    let (r, lc, hc) = (o.radius, o.length, o.grasp_height);
    let g = [x.placement.x_off, r, lc / 2.0 - hc];
    let (m, jc, ja) = (o.mass(), o.inertia(), o.mass() * r * r / 2.0);
    xml.comment(&format!(
        "the object: a solid cylinder, radius R = {} m, length L_c = {} m, axis z, standing on the ground, centre G = (x_off, R, L_c/2 − h_c) \
         touching the palm ({}, §14.1)",
        num(r),
        num(lc),
        if free { "a free body" } else { "fixed to the world: the object of the centred/offset scene, §8" }
    ));
    xml.open("body", &[a("name", "object"), a("pos", list(&g))]);
    if free {
        xml.empty("freejoint", &[a("name", "object_free")]);
    }
    xml.comment(&format!(
        "m_c = ρ_c π R² L_c = {} kg, J_c = m_c (3R² + L_c²)/12 = {} kg·m² (transverse), J_a = m_c R²/2 = {} kg·m² (§4, §14.1)",
        num(m),
        num(jc),
        num(ja)
    ));
    xml.empty("inertial", &[a("pos", "0 0 0"), a("mass", num(m)), a("diaginertia", list(&[jc, jc, ja]))]);
    xml.empty(
        "geom",
        &[a("name", "object"), a("class", "object"), a("type", "cylinder"), a("size", list(&[r, lc / 2.0]))],
    );
    xml.close();
}

fn loops(xml: &mut XmlWriter, x: &ExportedDesign, set: &MujocoSettings) {
    xml.open("equality", &[]);
    xml.comment(&format!(
        "the five-bar loops closed at O13 (§8.1: the tree is cut there): link 12's end (l12, 0) meets body 22's point (l22, 0); \
         MuJoCo's stiffest constraint (solref {}, solimp {})",
        list(&set.loop_solref),
        list(&set.loop_solimp)
    ));
    each_finger(xml, "connect", |pre| {
        vec![
            a("name", format!("{pre}_loop")),
            a("body1", format!("{pre}_link12")),
            a("body2", format!("{pre}_body22")),
            a("anchor", list(&[x.finger.l12, 0.0, 0.0])),
            a("solref", list(&set.loop_solref)),
            a("solimp", list(&set.loop_solimp)),
        ]
    });
    xml.close();
}

fn contacts(xml: &mut XmlWriter, x: &ExportedDesign, set: &MujocoSettings, free: bool) {
    let c = &x.scene.contact;
    let env = &x.scene.env;
    let pair = |name: String, g1: String, g2: &str, mu: f64| {
        vec![
            a("name", name),
            a("geom1", g1),
            a("geom2", g2),
            a("condim", "3"),
            a("friction", list(&[mu, mu, 0.0, 0.0, 0.0])),
            a("solref", list(&set.contact_solref)),
            a("solimp", list(&set.contact_solimp)),
        ]
    };
    xml.open("contact", &[]);
    xml.comment(&format!(
        "phalanx–object (§8.5–8.6): Coulomb friction μ = μ_d = {} (MuJoCo has one coefficient; MODEL.md: μ_s = {}, μ_d = {} \
         with a regularised STEP law). Normal: MuJoCo's soft contact, solref/solimp chosen for \
         the restitution e = {} (MODEL.md: Hertz K δ^1.5 with Flores damping, K = {} N/m^1.5), docs/export.md",
        num(c.mu_d),
        num(c.mu_s),
        num(c.mu_d),
        num(c.restitution),
        num(c.k_contact)
    ));
    for pre in ["f1", "f2"] {
        for ph in ["proximal", "distal"] {
            xml.empty("pair", &pair(format!("{pre}_{ph}_object"), format!("{pre}_{ph}"), "object", c.mu_d));
        }
    }
    if free {
        xml.comment(&format!("palm–object, friction μ_p = {} (§14.2)", num(env.mu_p)));
        xml.empty("pair", &pair("palm_object".into(), "palm".into(), "object", env.mu_p));
        xml.comment(&format!(
            "ground–object, friction μ_g = {} (§14.2; MODEL.md: 16 Hertz points on the base rim, MuJoCo: its cylinder–plane contact)",
            num(env.mu_g)
        ));
        xml.empty("pair", &pair("ground_object".into(), "ground".into(), "object", env.mu_g));
    }
    xml.close();
}

fn actuators(xml: &mut XmlWriter, x: &ExportedDesign) {
    let h = &x.scene.hand;
    let psi = x.finger.psi;
    xml.open("actuator", &[]);
    xml.comment(&format!(
        "the motor: torque τ = ctrl on q11 (link 11 about O11, closing), τ = {} N·m in MODEL.md (§1.1, §8.3); the keyframe `grasp` sets it",
        num(h.tau)
    ));
    each_finger(xml, "motor", |pre| {
        vec![
            a("name", format!("{pre}_motor")),
            a("joint", format!("{pre}_q11")),
            a("gear", "1"),
            a("ctrlrange", list(&[-h.tau, h.tau])),
        ]
    });
    xml.comment(&format!(
        "the spring at O22 between bodies 21 and 22, opening the distal phalanx (§6.2): generalised force −τ_s(θ2) on q22, \
         τ_s = τ_s0 + k_s θ2 = τ_s0 + k_s (q22 + ψ), τ_s0 = max(0, τ_s^min) = {} N·m (τ_s^min = {} N·m), k_s = {} N·m/rad: \
         a passive actuator (gain 0) whose bias is −τ_s0 − k_s ψ − k_s q22",
        num(x.tau_s0),
        num(x.tau_s_min),
        num(h.k_s)
    ));
    each_finger(xml, "general", |pre| {
        vec![
            a("name", format!("{pre}_spring")),
            a("joint", format!("{pre}_q22")),
            a("gainprm", "0"),
            a("biastype", "affine"),
            a("biasprm", list(&[-x.tau_s0 - h.k_s * psi, -h.k_s, 0.0])),
        ]
    });
    xml.close();
}

fn keyframe(xml: &mut XmlWriter, x: &ExportedDesign, free: bool, r: f64, lc: f64, hc: f64) {
    let o = &x.finger.open;
    let mut qpos = vec![];
    for _ in 0..2 {
        qpos.extend_from_slice(&[o.q11, o.q12, o.q21, o.q22]);
    }
    if free {
        qpos.extend_from_slice(&[x.placement.x_off, r, lc / 2.0 - hc, 1.0, 0.0, 0.0, 0.0]);
    }
    let tau = x.scene.hand.tau;
    xml.open("keyframe", &[]);
    xml.comment(
        "the open pose (§3.2, = qpos0) at rest with the motor torque τ on both fingers: the grasp of §8.7 from t = 0",
    );
    xml.empty("key", &[a("name", "grasp"), a("qpos", list(&qpos)), a("ctrl", list(&[tau, tau, 0.0, 0.0]))]);
    xml.close();
}
