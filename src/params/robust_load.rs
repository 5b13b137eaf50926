//! `[robust]` as written in a problem file and its validation: every key required (the
//! uncertain inputs are the ones listed), errors naming the file and the field.

use super::checker::Checker;
use super::robust::{corner_count, Aggregation, Certify, Robust, Sampling};
use super::scene::{Object, ObjectCase, SceneParams};
use super::uncertainty::{input_slot, phi, Dist, Uncertainty, INPUTS};
use crate::error::Result;
use serde::Deserialize;

/// Most objects of a robust problem.
pub const MAX_OBJECTS: usize = 16;
/// Most values of a list distribution.
const MAX_LIST: usize = 1000;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRobust {
    sampling: String,
    scenarios: f64,
    seed: u64,
    p_min: f64,
    confidence: f64,
    early_stop: bool,
    verify_scenarios: f64,
    aggregate: RawAggregate,
    objects: Vec<RawObjectCase>,
    uncertainty: RawUncertainty,
    #[serde(default)]
    certify: RawCertify,
}

/// `[robust.certify]` as written: every key optional (defaults from p_min).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawCertify {
    enabled: Option<bool>,
    confidence: Option<f64>,
    looks: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAggregate {
    max_offset: RawAgg,
    alpha: RawAgg,
    mean_force: RawAgg,
    t_stab: RawAgg,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawAgg {
    Quantile(f64),
    Word(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObjectCase {
    name: String,
    file: Option<String>,
    radius: Option<f64>,
    length: Option<f64>,
    density: Option<f64>,
    grasp_height: Option<f64>,
    tau: f64,
}

/// `[robust.uncertainty]` as written: a distribution per input named by its row of
/// [`INPUTS`] (an unknown name is refused naming the known ones).
#[derive(Deserialize, Default)]
#[serde(transparent)]
struct RawUncertainty(std::collections::BTreeMap<String, RawDist>);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDist {
    uniform: Option<Vec<f64>>,
    normal: Option<Vec<f64>>,
    list: Option<Vec<f64>>,
}

impl RawRobust {
    /// The checked `[robust]` of a problem whose other sections are `scene`.
    pub(super) fn validate(&self, scene: &SceneParams, c: &Checker<'_>) -> Result<Robust> {
        if !scene.setup.kind.is_free() {
            return Err(c.fail(
                "scene.kind",
                format!("{:?}", scene.setup.kind.as_str()),
                "must be \"free\" with [robust]: a scenario's verdict is the free object's motion (MODEL.md §14.4)",
            ));
        }
        let sampling = match self.sampling.as_str() {
            "random" => Sampling::Random,
            "corners" => Sampling::Corners,
            other => return Err(c.fail("robust.sampling", format!("{other:?}"), "must be \"random\" or \"corners\"")),
        };
        let scenarios = whole(c, "robust.scenarios", self.scenarios, 1.0, 4096.0)?;
        let verify_scenarios = whole(c, "robust.verify_scenarios", self.verify_scenarios, 1.0, 100_000.0)?;
        let p_min = self.p_min;
        if !(0.0..=1.0).contains(&p_min) {
            return Err(c.fail("robust.p_min", format!("{p_min}"), "must be a probability in [0, 1]"));
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return Err(c.fail("robust.confidence", format!("{}", self.confidence), "must be in (0, 1), e.g. 0.95"));
        }
        let a = &self.aggregate;
        let aggregate = [
            agg(c, "robust.aggregate.max_offset", &a.max_offset)?,
            agg(c, "robust.aggregate.alpha", &a.alpha)?,
            agg(c, "robust.aggregate.mean_force", &a.mean_force)?,
            agg(c, "robust.aggregate.t_stab", &a.t_stab)?,
        ];
        let objects = self.objects(scene, c)?;
        let uncertainty = self.uncertainty.validate(c)?;
        let certify = self.certify.validate(p_min, c)?;
        let robust = Robust {
            objects,
            uncertainty,
            sampling,
            scenarios,
            seed: self.seed,
            aggregate,
            p_min,
            confidence: self.confidence,
            early_stop: self.early_stop,
            verify_scenarios,
            certify,
        };
        check_supports(&robust, scene, c)?;
        if sampling == Sampling::Corners {
            let d = robust.uncertainty.uncertain().len();
            if d == 0 {
                return Err(c.fail("robust.sampling", "\"corners\"".into(), "needs at least one uncertain input"));
            }
            check_corner_centres(&robust, c)?;
            if scenarios != corner_count(d) {
                return Err(c.fail(
                    "robust.scenarios",
                    format!("{scenarios}"),
                    &format!(
                        "must be 1 + 2^{d} = {} with sampling = \"corners\" ({d} uncertain inputs)",
                        corner_count(d)
                    ),
                ));
            }
        }
        Ok(robust)
    }

    fn objects(&self, scene: &SceneParams, c: &Checker<'_>) -> Result<Vec<ObjectCase>> {
        if self.objects.is_empty() {
            return Err(c.fail("robust.objects", "[]".into(), "must list at least one object ([[robust.objects]])"));
        }
        if self.objects.len() > MAX_OBJECTS {
            let n = self.objects.len();
            return Err(c.fail("robust.objects", format!("{n} objects"), &format!("at most {MAX_OBJECTS}")));
        }
        let mut out: Vec<ObjectCase> = Vec::new();
        for (i, o) in self.objects.iter().enumerate() {
            let field = |f: &str| format!("robust.objects[{i}].{f}");
            let ok =
                !o.name.is_empty() && o.name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_');
            if !ok {
                return Err(c.fail(
                    &field("name"),
                    format!("{:?}", o.name),
                    "must be letters, digits, - or _ (a CSV column prefix)",
                ));
            }
            if out.iter().any(|p| p.name == o.name) {
                return Err(c.fail(&field("name"), format!("{:?}", o.name), "names another object already"));
            }
            let inline = [o.radius, o.length, o.density, o.grasp_height];
            let object = match (&o.file, inline.iter().all(Option::is_some), inline.iter().any(Option::is_some)) {
                (Some(f), _, false) => {
                    let path = c.file.parent().unwrap_or(std::path::Path::new(".")).join(f);
                    object_of_file(&path).map_err(|e| {
                        c.fail(&field("file"), format!("{f:?}"), &format!("must be a problem file with a valid [object] (paths are relative to this file; a run folder keeps only its problem.toml: inline the object there): {e}"))
                    })?
                }
                (None, true, _) => {
                    let chk = |name: &str, v: Option<f64>| -> Result<f64> {
                        let v = v.expect("all four given");
                        super::limits::limit(&format!("object.{name}"))
                            .check(v)
                            .map_err(|rule| c.fail(&field(name), super::limits::num(v), &rule))
                    };
                    Object {
                        radius: chk("radius", o.radius)?,
                        length: chk("length", o.length)?,
                        density: chk("density", o.density)?,
                        grasp_height: chk("grasp_height", o.grasp_height)?,
                    }
                }
                _ => {
                    return Err(c.fail(
                        &field("file"),
                        o.file.clone().unwrap_or_default(),
                        "give either `file` (a problem file whose [object] is taken) or all of radius, length, density, grasp_height",
                    ))
                }
            };
            if object.grasp_height >= object.length {
                return Err(c.fail(
                    &field("grasp_height"),
                    format!("{}", object.grasp_height),
                    &format!("must be below the object's top (length {})", object.length),
                ));
            }
            if object.grasp_height < scene.hand.w {
                return Err(c.fail(
                    &field("grasp_height"),
                    format!("{}", object.grasp_height),
                    &super::checker::below_finger_rule(scene.hand.w),
                ));
            }
            let tau = super::limits::limit("hand.tau")
                .check(o.tau)
                .map_err(|rule| c.fail(&field("tau"), super::limits::num(o.tau), &rule))?;
            out.push(ObjectCase { name: o.name.clone(), object, tau, file: o.file.clone() });
        }
        Ok(out)
    }
}

impl RawCertify {
    fn validate(&self, p_min: f64, c: &Checker<'_>) -> Result<Certify> {
        let confidence = self.confidence.unwrap_or(0.95);
        if !(confidence > 0.0 && confidence < 1.0) {
            return Err(c.fail("robust.certify.confidence", format!("{confidence}"), "must be in (0, 1), e.g. 0.95"));
        }
        // p_min 0 has no chance constraint to certify, p_min 1 no finite sample certifies:
        // certification is on by default in between
        let enabled = self.enabled.unwrap_or(p_min > 0.0 && p_min < 1.0);
        if enabled && p_min == 0.0 {
            return Err(c.fail(
                "robust.certify.enabled",
                "true".into(),
                "p_min = 0 sets no chance constraint to certify (leave [robust.certify] out)",
            ));
        }
        let looks = match (&self.looks, Certify::default_looks(p_min, confidence)) {
            (Some(v), _) => {
                let mut looks = Vec::with_capacity(v.len());
                for (i, &n) in v.iter().enumerate() {
                    let n = whole(c, &format!("robust.certify.looks[{i}]"), n, 1.0, 4096.0)?;
                    if looks.last().is_some_and(|&m| n <= m) {
                        return Err(c.fail(
                            "robust.certify.looks",
                            format!("{v:?}"),
                            "must increase (scenarios per object at each look)",
                        ));
                    }
                    looks.push(n);
                }
                if looks.is_empty() || looks.len() > 8 {
                    return Err(c.fail("robust.certify.looks", format!("{v:?}"), "must hold 1 to 8 looks"));
                }
                looks
            }
            (None, Some(d)) => d,
            // p_min 0 (no chance constraint) or 1 (no sample certifies): nothing to plan
            (None, None) => vec![],
        };
        let plan = Certify { enabled, confidence, looks };
        if enabled {
            if let Err(why) = plan.check(p_min) {
                return Err(c.fail("robust.certify.looks", format!("{:?}", plan.looks), &why));
            }
        }
        Ok(plan)
    }
}

impl RawUncertainty {
    fn validate(&self, c: &Checker<'_>) -> Result<Uncertainty> {
        let mut u = Uncertainty::default();
        for (name, r) in &self.0 {
            let field = format!("robust.uncertainty.{name}");
            let Some(i) = input_slot(name) else {
                let known: Vec<&str> = INPUTS.iter().map(|r| r.name).collect();
                return Err(c.fail(
                    &field,
                    "{…}".into(),
                    &format!("is not an uncertain input (known: {})", known.join(", ")),
                ));
            };
            u.inputs[i] = Some(r.validate(c, &field)?);
        }
        Ok(u)
    }
}

impl RawDist {
    fn validate(&self, c: &Checker<'_>, field: &str) -> Result<Dist> {
        let given = [&self.uniform, &self.normal, &self.list];
        if given.iter().filter(|g| g.is_some()).count() != 1 {
            return Err(c.fail(
                field,
                "{…}".into(),
                "must be exactly one of uniform = [lo, hi], normal = [mean, sd, lo, hi], list = [v1, v2, …]",
            ));
        }
        let finite = |v: &[f64], what: &str| -> Result<()> {
            match v.iter().find(|x| !x.is_finite()) {
                Some(x) => Err(c.fail(&format!("{field}.{what}"), format!("{x}"), "must be finite numbers")),
                None => Ok(()),
            }
        };
        if let Some(v) = &self.uniform {
            finite(v, "uniform")?;
            if v.len() != 2 {
                return Err(c.fail(&format!("{field}.uniform"), format!("{v:?}"), "must be [lo, hi]: two numbers"));
            }
            if v[0] >= v[1] {
                return Err(c.fail(
                    &format!("{field}.uniform"),
                    format!("{v:?}"),
                    "lo must be < hi (a fixed value: leave the input out)",
                ));
            }
            return Ok(Dist::Uniform { lo: v[0], hi: v[1] });
        }
        if let Some(v) = &self.normal {
            finite(v, "normal")?;
            let f = format!("{field}.normal");
            if v.len() != 4 {
                return Err(c.fail(
                    &f,
                    format!("{v:?}"),
                    "must be [mean, sd, lo, hi]: four numbers (the bounds are required)",
                ));
            }
            let (mean, sd, lo, hi) = (v[0], v[1], v[2], v[3]);
            if !(sd > 0.0) {
                return Err(c.fail(&f, format!("{v:?}"), "the standard deviation (second number) must be > 0"));
            }
            if lo >= hi {
                return Err(c.fail(&f, format!("{v:?}"), "the bounds must be lo < hi (third < fourth number)"));
            }
            if phi((hi - mean) / sd) - phi((lo - mean) / sd) < 1e-9 {
                return Err(c.fail(&f, format!("{v:?}"), "the bounds hold almost none of the distribution"));
            }
            return Ok(Dist::Normal { mean, sd, lo, hi });
        }
        let v = self.list.as_ref().expect("one given");
        finite(v, "list")?;
        if v.is_empty() || v.len() > MAX_LIST {
            return Err(c.fail(&format!("{field}.list"), format!("{} values", v.len()), "must hold 1 to 1000 values"));
        }
        Ok(Dist::List(v.clone()))
    }
}

/// The centre scenario of `sampling = "corners"` takes each input's centre (a normal's
/// mean): it must be a value a draw can take, within the input's bounds, which
/// [`check_supports`] checked (a mean outside them gave a negative friction or torque).
fn check_corner_centres(r: &Robust, c: &Checker<'_>) -> Result<()> {
    for (i, d) in r.uncertainty.inputs.iter().enumerate() {
        let Some(d) = d else { continue };
        let ((lo, hi), centre) = (d.support(), d.centre());
        if !(lo..=hi).contains(&centre) {
            return Err(c.fail(
                &format!("robust.uncertainty.{}", INPUTS[i].name),
                super::robust::describe(d),
                &format!(
                    "with sampling = \"corners\" the centre scenario takes the mean {centre}, which must lie within the bounds [{lo}, {hi}]"
                ),
            ));
        }
    }
    Ok(())
}

/// Every value a draw can take keeps each object's inputs in their admissible range (no
/// negative friction, restitution in [0.01, 0.99], the grasp on the cylinder's side, …: each
/// input's own rule, [`InputRow::admissible`](super::InputRow)).
fn check_supports(r: &Robust, scene: &SceneParams, c: &Checker<'_>) -> Result<()> {
    for (row, d) in INPUTS.iter().zip(&r.uncertainty.inputs) {
        let Some(d) = d else { continue };
        let (lo, hi) = d.support();
        let field = format!("robust.uncertainty.{}", row.name);
        for o in &r.objects {
            (row.admissible)(lo, hi, o, scene)
                .map_err(|rule| c.fail(&field, format!("draws in [{lo}, {hi}]"), &rule))?;
        }
    }
    Ok(())
}

/// The `[object]` of another problem file (only that section is read: a file that names
/// objects of its own cannot make a cycle).
fn object_of_file(path: &std::path::Path) -> std::result::Result<Object, String> {
    use std::io::Read;
    let file = crate::fsutil::open_regular(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut text = String::new();
    file.take(super::limits::MAX_FILE_BYTES)
        .read_to_string(&mut text)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let raw = table.get("object").ok_or_else(|| format!("{}: no [object] section", path.display()))?;
    let o: Object = raw.clone().try_into().map_err(|e| format!("{}: [object]: {e}", path.display()))?;
    for (name, v) in
        [("radius", o.radius), ("length", o.length), ("density", o.density), ("grasp_height", o.grasp_height)]
    {
        super::limits::limit(&format!("object.{name}"))
            .check(v)
            .map_err(|rule| format!("{}: object.{name} = {v} {rule}", path.display()))?;
    }
    Ok(o)
}

fn whole(c: &Checker<'_>, field: &str, v: f64, lo: f64, hi: f64) -> Result<usize> {
    if !v.is_finite() || v.fract() != 0.0 || v < lo || v > hi {
        return Err(c.fail(field, format!("{v}"), &format!("must be a whole number in [{lo}, {hi}]")));
    }
    Ok(v as usize)
}

fn agg(c: &Checker<'_>, field: &str, a: &RawAgg) -> Result<Aggregation> {
    match a {
        RawAgg::Word(w) if w == "worst" => Ok(Aggregation::Worst),
        RawAgg::Word(w) if w == "mean" => Ok(Aggregation::Mean),
        RawAgg::Quantile(q) if *q > 0.0 && *q <= 1.0 => Ok(Aggregation::Quantile(*q)),
        RawAgg::Quantile(q) => Err(c.fail(field, format!("{q}"), "a quantile must be a probability in (0, 1]")),
        RawAgg::Word(w) => Err(c.fail(
            field,
            format!("{w:?}"),
            "must be \"worst\", \"mean\" or a quantile q in (0, 1] (the value at least a fraction q of the scenarios meet)",
        )),
    }
}
