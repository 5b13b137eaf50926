//! The four objectives as every output reports them: the run's CSV rows, `/designs`, a
//! design's [`Record`](super::Record) and the robust record's aggregated and per-object
//! objectives.

use crate::params::Criteria;
use serde::{Deserialize, Serialize};

/// The four objectives in their natural sense (MODEL.md §10): a design's, or a robust
/// design's aggregated or per object; `None` where not computed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Objectives {
    /// Objective 1: the largest object offset still form closed (m, maximise).
    pub max_offset: Option<f64>,
    /// Objective 2: force isotropy α (minimise).
    pub alpha: Option<f64>,
    /// Objective 3: mean contact force F̃ (N, maximise).
    pub mean_force: Option<f64>,
    /// Objective 4: time to stability (s, minimise).
    pub t_stab: Option<f64>,
}

impl Objectives {
    /// The objectives in the order max_offset, α, F̃, t_stab.
    pub fn from_array([max_offset, alpha, mean_force, t_stab]: [Option<f64>; 4]) -> Self {
        Objectives { max_offset, alpha, mean_force, t_stab }
    }
    /// In the order max_offset, α, F̃, t_stab.
    pub fn to_array(&self) -> [Option<f64>; 4] {
        [self.max_offset, self.alpha, self.mean_force, self.t_stab]
    }
    /// As the outputs report them: max_offset only when form closed (MODEL.md §6.7: a
    /// design not form closed at 0 carries max_offset = −Δ_off inside the optimiser, a
    /// placeholder never reported).
    pub fn reported(self) -> Self {
        Objectives { max_offset: self.max_offset.filter(|m| *m >= 0.0), ..self }
    }
}

/// Which way an objective is better.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sense {
    /// Larger is better.
    Maximise,
    /// Smaller is better.
    Minimise,
}

impl Sense {
    /// The factor that turns a value into minimisation form (−1 for a maximised one).
    pub fn sign(self) -> f64 {
        match self {
            Sense::Maximise => -1.0,
            Sense::Minimise => 1.0,
        }
    }
    /// "maximise" or "minimise".
    pub fn word(self) -> &'static str {
        match self {
            Sense::Maximise => "maximise",
            Sense::Minimise => "minimise",
        }
    }
    /// "higher" or "lower" (is better).
    pub fn better(self) -> &'static str {
        match self {
            Sense::Maximise => "higher",
            Sense::Minimise => "lower",
        }
    }
}

/// One of the four objectives of MODEL.md §10: a row of [`OBJECTIVES`], the one place its
/// name, unit, sense, display and placeholder are written; every output, plot, label and the
/// optimiser's minimisation form read it.
#[derive(Debug, Clone, Copy)]
pub struct Objective {
    /// Its name (the record's key, the CSV column).
    pub name: &'static str,
    /// Its unit (`-`: none).
    pub unit: &'static str,
    /// What it is (a table column's meaning).
    pub meaning: &'static str,
    /// Its label on a plot axis.
    pub label: &'static str,
    /// Which way is better.
    pub sense: Sense,
    /// Its display unit and the factor from `unit` to it (plots and reports: mm, ms).
    pub shown: (&'static str, f64),
    /// MODEL.md §10's finite placeholder of a missing value in minimisation form, from the
    /// problem's criteria (never compared: only feasible designs are ranked by objectives).
    pub placeholder: fn(&Criteria) -> f64,
}

impl Objective {
    /// Value `v` (natural sense) in minimisation form; the placeholder where it is missing
    /// or not finite.
    pub fn minimised(&self, v: Option<f64>, c: &Criteria) -> f64 {
        v.map(|v| self.sense.sign() * v).filter(|m| m.is_finite()).unwrap_or_else(|| (self.placeholder)(c))
    }
    /// Its column of a design table: name, unit, meaning.
    pub const fn column(&self) -> (&'static str, &'static str, &'static str) {
        (self.name, self.unit, self.meaning)
    }
    /// The axis or column label of a plot: "max_offset (mm), higher better".
    pub fn axis(&self) -> String {
        let unit = if self.shown.0 == "-" { String::new() } else { format!(" ({})", self.shown.0) };
        format!("{}{unit}, {} better", self.label, self.sense.better())
    }
}

/// The four objectives, in their order (max_offset, α, F̃, t_stab).
pub const OBJECTIVES: [Objective; 4] = [
    Objective {
        name: "max_offset",
        unit: "m",
        meaning: "objective, MAXIMISE: largest object offset still form closed",
        label: "max_offset",
        sense: Sense::Maximise,
        shown: ("mm", 1e3),
        placeholder: |c| c.offset_step,
    },
    Objective {
        name: "alpha",
        unit: "-",
        meaning: "objective, MINIMISE: force isotropy (force model in force_model)",
        label: "alpha",
        sense: Sense::Minimise,
        shown: ("-", 1.0),
        placeholder: |_| 1e6,
    },
    Objective {
        name: "mean_force",
        unit: "N",
        meaning: "objective, MAXIMISE: mean contact force",
        label: "mean force",
        sense: Sense::Maximise,
        shown: ("N", 1.0),
        placeholder: |_| 0.0,
    },
    Objective {
        name: "t_stab",
        unit: "s",
        meaning: "objective, MINIMISE: time to stability",
        label: "t_stab",
        sense: Sense::Minimise,
        shown: ("ms", 1e3),
        placeholder: |c| c.t_max,
    },
];

/// Natural-sense values `v` (in the order of [`OBJECTIVES`]) in minimisation form, with the
/// placeholders of `c` where one is missing or not finite.
pub fn minimised(v: [Option<f64>; 4], c: &Criteria) -> [f64; 4] {
    std::array::from_fn(|k| OBJECTIVES[k].minimised(v[k], c))
}

/// The names of the objectives, in order.
pub fn objective_names() -> [&'static str; 4] {
    OBJECTIVES.map(|o| o.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn criteria() -> Criteria {
        let p = crate::params::Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap();
        p.scene.criteria
    }

    /// MODEL.md §10: minimisation form is (−max_offset, α, −F̃, t_stab), a missing or
    /// non-finite value the finite placeholder (Δ_off, 10⁶, 0, t_max), written out here.
    #[test]
    fn minimisation_form_and_placeholders_are_model_10s() {
        let c = criteria();
        let v = [Some(0.004), Some(0.3), Some(12.5), Some(0.02)];
        assert_eq!(minimised(v, &c), [-0.004, 0.3, -12.5, 0.02]);
        // the −Δ_off of a design not form closed stays a value (ranked, never reported)
        assert_eq!(minimised([Some(-c.offset_step), None, None, None], &c)[0], c.offset_step);
        let none = minimised([None, Some(f64::INFINITY), Some(f64::NAN), None], &c);
        assert_eq!(none, [c.offset_step, 1e6, 0.0, c.t_max]);
        assert_eq!(objective_names(), ["max_offset", "alpha", "mean_force", "t_stab"]);
        assert_eq!(OBJECTIVES[0].axis(), "max_offset (mm), higher better");
        assert_eq!(OBJECTIVES[1].axis(), "alpha, lower better");
    }

    /// The table agrees with the record's type: its names are [`Objectives`]' keys, in order.
    #[test]
    fn the_table_names_the_records_objectives() {
        let o = Objectives { max_offset: Some(1.0), alpha: Some(2.0), mean_force: Some(3.0), t_stab: Some(4.0) };
        let v = serde_json::to_value(o).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        let mut names = objective_names().to_vec();
        names.sort_unstable();
        assert_eq!(keys, names);
        for (k, n) in objective_names().iter().enumerate() {
            assert_eq!(v[n], serde_json::json!(o.to_array()[k].unwrap()));
        }
    }
}
