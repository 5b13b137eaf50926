//! The build sheet of an exported design, for CAD and for building the prototype: every
//! length and angle (mm, degrees), the joint positions in the palm frame at the open pose
//! and at the closed pose on the object, link masses and inertias, the spring and motor
//! torques. One list of rows, written as JSON (sections of `name_unit: value`) or CSV
//! (`section,name,value,unit,description`).

use super::{num, ExportedDesign, ObjectMode};
use crate::cells::quoted;
use crate::math::V2;
use crate::model::{closed_pose, to_world, Finger, Pose};
use serde::ser::{Serialize, SerializeMap, Serializer};

/// One quantity of the build sheet.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetRow {
    /// Section (`design`, `lengths`, `open_pose`, …).
    pub section: &'static str,
    /// Quantity name (MODEL.md's symbol where it has one).
    pub name: String,
    /// Value in `unit`.
    pub value: f64,
    /// Unit (`mm`, `deg`, `g`, `N·m`, … ; empty for pure numbers).
    pub unit: &'static str,
    /// What it is.
    pub description: String,
}

/// The build sheet: where the design comes from and its rows, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildSheet {
    /// The design's source (problem file or run folder and id).
    pub source: String,
    /// Stages 0–2: `None` when the design passes them, else why it was discarded.
    pub statics_discard: Option<String>,
    /// The rows.
    pub rows: Vec<SheetRow>,
}

const MM: f64 = 1e3;

struct Rows(Vec<SheetRow>);

impl Rows {
    fn add(&mut self, section: &'static str, name: &str, value: f64, unit: &'static str, description: &str) {
        self.0.push(SheetRow { section, name: name.into(), value, unit, description: description.into() });
    }
    fn point(&mut self, section: &'static str, name: &str, p: V2, description: &str) {
        self.add(section, &format!("{name}_x"), p.x * MM, "mm", &format!("{description}, x"));
        self.add(section, &format!("{name}_y"), p.y * MM, "mm", &format!("{description}, y"));
    }
    /// Joint points of both fingers at pose `p` of finger 1 (finger 2 is its mirror).
    fn joints(&mut self, section: &'static str, f: &Finger, p: &Pose) {
        let pts = [
            ("O11", f.o21, "actuated joint O11 = O21 (link 11 and proximal phalanx on one axis)"),
            ("O12", p.o12, "joint O12 between link 11 and link 12"),
            ("O22", p.o22, "joint O22 between the proximal phalanx and body 22 (the spring's axis)"),
            ("O13", p.o13, "joint O13 between link 12 and link 22 (the loop closure)"),
            ("tip", f.tip(p), "distal phalanx tip (axis end)"),
        ];
        for (j, name) in ["finger1", "finger2"].iter().enumerate() {
            for (pn, pt, what) in pts {
                self.point(section, &format!("{name}_{pn}"), to_world(pt, j), &format!("{name}: {what}"));
            }
        }
    }
    fn angles(&mut self, section: &'static str, f: &Finger, p: &Pose) {
        let (t1, t2) = p.theta(f.psi);
        let a = [
            ("q11", p.q11, "absolute angle of link 11"),
            ("q12", p.q12, "angle from link 11 to link 12"),
            ("q21", p.q21, "absolute angle of the proximal phalanx (= θ1)"),
            ("q22", p.q22, "angle from the proximal phalanx to link 22"),
            ("q13", p.q13, "angle from link 12 to link 22"),
            ("theta1", t1, "proximal phalanx angle θ1"),
            ("theta2", t2, "distal phalanx angle θ2 relative to the proximal (0 = straight, on the stop)"),
        ];
        for (n, v, d) in a {
            self.add(section, n, v.to_degrees(), "deg", &format!("{d} (finger 1; finger 2 mirrored)"));
        }
    }
}

/// The build sheet of `x`.
pub fn build_sheet(x: &ExportedDesign) -> BuildSheet {
    let f = &x.finger;
    let s = &x.scene;
    let d = &x.design;
    let mut r = Rows(vec![]);
    r.add("design", "l21", d.l21 * MM, "mm", "proximal phalanx length (O21 → O22)");
    r.add("design", "b", d.b * MM, "mm", "palm length: distance between the two base joints");
    r.add("design", "t22", d.t22 * MM, "mm", "distal phalanx length (O22 → tip)");
    r.add("design", "r", d.r, "", "transmission ratio l22/l11");
    r.add("design", "p", d.p, "", "ratio l11/l21");
    r.add("design", "psi", d.psi.to_degrees(), "deg", "distal angle ψ from link 22 to the distal phalanx");
    r.add("design", "l_hand", d.l_hand() * MM, "mm", "hand length b + 2 t22 + 2 l21");
    r.add("lengths", "l11", f.l11 * MM, "mm", "link 11 (actuated crank), O11 → O12");
    r.add("lengths", "l12", f.l12 * MM, "mm", "link 12 (transmission bar), O12 → O13");
    r.add("lengths", "l21", f.l21 * MM, "mm", "link 21 (proximal phalanx), O21 → O22");
    r.add("lengths", "l22", f.l22 * MM, "mm", "link 22 (distal lever), O22 → O13");
    r.add("lengths", "t22", f.t22 * MM, "mm", "distal phalanx, O22 → tip, at ψ from link 22");
    r.add("lengths", "w", f.w * MM, "mm", "rod radius of every link (diameter 2w)");
    r.add("lengths", "k10", f.k10 * MM, "mm", "open-pose tangent length k10 (MODEL.md eq. 4.3)");
    r.add("assembly", "gamma", f.gamma, "", "assembly mode Γ (sign of cross(O12 − O22, O13 − O22))");
    r.add("assembly", "sigma", f.sigma, "", "leg-1 working mode σ (sign of sin q12)");
    r.angles("open_pose", f, &f.open);
    r.joints("open_pose", f, &f.open);
    let (rad, x_c) = (s.object.radius, 0.0);
    match closed_pose(f, rad, x_c) {
        Ok(cp) => {
            r.angles("closed_pose", f, &cp.pose);
            r.joints("closed_pose", f, &cp.pose);
            r.add("closed_pose", "k1", cp.k1 * MM, "mm", "contact abscissa on the proximal phalanx from O21");
            r.add("closed_pose", "k2", cp.k2 * MM, "mm", "contact abscissa on the distal phalanx from O22");
        }
        Err(e) => {
            r.add("closed_pose", "exists", 0.0, "", &format!("no closed pose on the centred object: {}", e.reason()))
        }
    }
    let names = ["link 11", "link 12", "link 21 (proximal phalanx)", "body 22 (link 22 + distal phalanx)"];
    for (k, n) in ["m11", "m12", "m21", "m22"].iter().enumerate() {
        r.add("masses", n, f.mass.m[k] * 1e3, "g", &format!("mass of {} (rods of density ρ_f, radius w)", names[k]));
    }
    r.add("masses", "m_finger", f.mass.m.iter().sum::<f64>() * 1e3, "g", "one finger's moving mass");
    for (k, n) in ["I11", "I12", "I21", "I22"].iter().enumerate() {
        r.add("masses", n, f.mass.i[k] * 1e9, "g·mm²", &format!("inertia of {} about its joint (z)", names[k]));
    }
    r.point("masses", "S22", f.mass.s22, "centre of mass of body 22 in its frame (x along link 22)");
    r.add("masses", "rho_f", s.hand.rho_f, "kg/m³", "finger density");
    r.add("torques", "tau", s.hand.tau, "N·m", "motor torque on link 11 (closing)");
    r.add("torques", "tau_s0", x.tau_s0, "N·m", "spring preload at O22 (opening the distal phalanx) at θ2 = 0");
    r.add(
        "torques",
        "tau_s_min",
        x.tau_s_min,
        "N·m",
        "minimal preload keeping the distal on its stop at rest (MODEL.md §6.2)",
    );
    r.add("torques", "k_s", s.hand.k_s, "N·m/rad", "spring rate: τ_s = τ_s0 + k_s θ2");
    r.add(
        "torques",
        "k_stop",
        s.hand.k_stop,
        "N·m/rad",
        "distal stop stiffness at θ2 = 0 (Hunt–Crossley, MODEL.md §8.4)",
    );
    r.add("torques", "c_stop", s.hand.c_stop, "s/rad", "distal stop damping factor");
    let o = &s.object;
    r.add("object", "R", o.radius * MM, "mm", "object (cylinder) radius");
    r.add("object", "L_c", o.length * MM, "mm", "cylinder length");
    r.add("object", "m_c", o.mass() * 1e3, "g", "object mass");
    r.add("object", "h_c", o.grasp_height * MM, "mm", "height of the hand plane above the ground");
    r.add("object", "x_off", x.placement.x_off * MM, "mm", "object offset along the palm");
    r.add(
        "object",
        "free",
        f64::from(u8::from(x.placement.object == ObjectMode::Free)),
        "",
        "1: free object, 0: fixed",
    );
    BuildSheet { source: x.source.clone(), statics_discard: x.statics_discard.clone(), rows: r.0 }
}

impl BuildSheet {
    /// The key of a row in JSON: `name_unit` (units spelt in ASCII), or `name` without unit.
    pub fn key(row: &SheetRow) -> String {
        let unit = match row.unit {
            "" => return row.name.clone(),
            "kg/m³" => "kg_m3",
            "N·m" => "Nm",
            "N·m/rad" => "Nm_per_rad",
            "s/rad" => "s_per_rad",
            "g·mm²" => "g_mm2",
            u => u,
        };
        format!("{}_{unit}", row.name)
    }

    /// CSV text: a `#` line with the source, then `section,name,value,unit,description`.
    pub fn to_csv(&self) -> String {
        let mut o = format!("# gripopt build sheet; source: {}\n", self.source.replace('\n', " "));
        o.push_str("section,name,value,unit,description\n");
        for r in &self.rows {
            o.push_str(&format!(
                "{},{},{},{},{}\n",
                r.section,
                quoted(&r.name),
                num(r.value),
                quoted(r.unit),
                quoted(&r.description)
            ));
        }
        o
    }

    /// Pretty JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a build sheet serialises") + "\n"
    }
}

/// One section as a JSON object of `key: value`, in row order.
struct Section<'a>(&'a [SheetRow]);

impl Serialize for Section<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for r in self.0 {
            m.serialize_entry(&BuildSheet::key(r), &r.value)?;
        }
        m.end()
    }
}

impl Serialize for BuildSheet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("format", "gripopt build sheet")?;
        m.serialize_entry("version", &1)?;
        m.serialize_entry("source", &self.source)?;
        m.serialize_entry("stages_0_2", &self.statics_discard.as_deref().unwrap_or("passes"))?;
        m.serialize_entry("frame", "palm frame of MODEL.md §2: origin at the palm centre, x along the palm toward finger 1, y toward the object")?;
        let mut start = 0;
        while start < self.rows.len() {
            let sec = self.rows[start].section;
            let end = start + self.rows[start..].iter().take_while(|r| r.section == sec).count();
            m.serialize_entry(sec, &Section(&self.rows[start..end]))?;
            start = end;
        }
        let desc: Vec<_> =
            self.rows.iter().map(|r| (format!("{}.{}", r.section, BuildSheet::key(r)), &r.description)).collect();
        m.serialize_entry("descriptions", &Descriptions(&desc))?;
        m.end()
    }
}

struct Descriptions<'a>(&'a [(String, &'a String)]);

impl Serialize for Descriptions<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}
