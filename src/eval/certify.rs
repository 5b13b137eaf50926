//! Certification of a robust design on fresh scenarios (issue 41, docs/robust.md
//! "Certification"): per object a group-sequential one-sided exact binomial test of
//! H₀: P(stay) < p_min. At each look i (n_i scenarios of the object, from a stream neither the
//! search nor `verify` uses) the object is certified when its stays s reach the fewest that
//! reject H₀ at level α/L (Bonferroni over the L looks: P(S ≥ s | n_i, p_min) ≤ α/L, so the
//! chance of certifying an object whose P(stay) is p_min or less is at most α whatever the
//! looks see). An object is given up once its failures exceed what the last look allows; a
//! design is certified when every object is, and stops at its first object given up. An
//! aborted scenario (the solver's failure) counts as a failure: nothing was measured.

use super::binomial::binomial_cdf;
use super::chance::chance_record;
use super::objectives::Objectives;
use super::record_robust::ScenarioRecord;
use super::scenario::DesignStart;
use super::study::Study;
use crate::params::Certify;
use serde::{Deserialize, Serialize};

/// The test of a certification: the looks and, per look, the fewest stays that certify.
#[derive(Debug, Clone, PartialEq)]
pub struct CertifyPlan {
    /// The constraint P(stay) ≥ p_min.
    pub p_min: f64,
    /// 1 − α.
    pub confidence: f64,
    /// Scenarios per object at each look, increasing.
    pub looks: Vec<usize>,
    /// Per look the fewest stays that reject H₀ at α/L (more than the look's scenarios when
    /// no count can).
    pub min_stays: Vec<usize>,
}

impl CertifyPlan {
    /// The plan of `[robust.certify]` `c` for `p_min`.
    pub fn new(c: &Certify, p_min: f64) -> Self {
        let a = (1.0 - c.confidence) / c.looks.len().max(1) as f64;
        let min_stays =
            c.looks.iter().map(|&n| (0..=n).find(|&s| upper_tail(s, n, p_min) <= a).unwrap_or(n + 1)).collect();
        CertifyPlan { p_min, confidence: c.confidence, looks: c.looks.clone(), min_stays }
    }

    /// α/L: the level of each look.
    pub fn alpha_per_look(&self) -> f64 {
        (1.0 - self.confidence) / self.looks.len().max(1) as f64
    }

    /// Scenarios per object at the last look.
    pub fn last(&self) -> usize {
        self.looks.last().copied().unwrap_or(0)
    }

    /// The most failures an object may have and still be certified at the last look.
    pub fn max_failures(&self) -> usize {
        let n = self.last();
        n.saturating_sub(*self.min_stays.last().unwrap_or(&(n + 1)))
    }

    /// The one-sided lower confidence bound on P(stay) after `stays` of `n` at level
    /// 1 − α/L: the p that solves P(S ≥ stays | n, p) = α/L (0 for no stay). An object is
    /// certified at a look exactly when this bound reaches p_min.
    pub fn lower_bound(&self, stays: usize, n: usize) -> f64 {
        if stays == 0 || n == 0 {
            return 0.0;
        }
        let a = self.alpha_per_look();
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        for _ in 0..200 {
            let m = 0.5 * (lo + hi);
            if upper_tail(stays, n, m) < a {
                lo = m;
            } else {
                hi = m;
            }
            if hi - lo < 1e-14 {
                break;
            }
        }
        0.5 * (lo + hi)
    }

    /// What the test decides of an object after `stays` of `runs` scenarios (in their order).
    pub fn decide(&self, stays: usize, runs: usize) -> ObjectDecision {
        if runs - stays > self.max_failures() {
            return ObjectDecision::GivenUp;
        }
        match self.looks.iter().position(|&n| n == runs) {
            Some(i) if stays >= self.min_stays[i] => ObjectDecision::Certified(i),
            _ => ObjectDecision::Open,
        }
    }

    /// The probability that an object whose true P(stay) is `p` is certified (the test's
    /// operating characteristic), exact: the distribution of its stays carried look by look,
    /// stopped where it certifies or is given up.
    pub fn probability_certified(&self, p: f64) -> f64 {
        // dist[f] = P(open with f failures after the scenarios so far)
        let mut dist = vec![1.0];
        let mut runs = 0;
        let mut certified = 0.0;
        for (i, &n) in self.looks.iter().enumerate() {
            for _ in runs..n {
                let mut next = vec![0.0; dist.len() + 1];
                for (f, &q) in dist.iter().enumerate() {
                    next[f] += q * p;
                    next[f + 1] += q * (1.0 - p);
                }
                next.truncate(self.max_failures() + 1);
                dist = next;
            }
            runs = n;
            for (f, q) in dist.iter_mut().enumerate() {
                if n - f >= self.min_stays[i] {
                    certified += *q;
                    *q = 0.0;
                }
            }
        }
        certified
    }
}

/// P(S ≥ s | n, p).
fn upper_tail(s: usize, n: usize, p: f64) -> f64 {
    if s == 0 {
        1.0
    } else {
        1.0 - binomial_cdf(s as u64 - 1, n as u64, p)
    }
}

/// What the test says of one object so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectDecision {
    /// Certified at look i.
    Certified(usize),
    /// More failures than the last look allows: it cannot be certified.
    GivenUp,
    /// Not decided yet.
    Open,
}

/// One object of a design's certification.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ObjectCertification {
    /// Its name.
    pub name: String,
    /// Fresh scenarios run.
    pub scenarios: usize,
    /// Of them, those in which it stayed.
    pub stays: usize,
    /// The one-sided lower confidence bound on P(stay) at level 1 − α/L.
    pub p_stay_lower: f64,
    /// Certified (None: not decided — the design stopped on another object first).
    pub certified: Option<bool>,
    /// The look (scenarios) at which it was certified.
    pub look: Option<usize>,
}

/// A design's certification.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CertificationRecord {
    /// Every object certified: P(stay) ≥ p_min on each at the plan's confidence.
    pub certified: bool,
    /// Per object.
    pub objects: Vec<ObjectCertification>,
    /// The objectives estimated on the fresh scenarios (max_offset, α, F̃ of stage 2;
    /// t_stab aggregated over the fresh scenarios run, as the search aggregates it).
    pub objectives: Objectives,
    /// Fresh scenarios run.
    pub scenarios_run: usize,
    /// Why it is not certified (None when it is).
    pub reason: Option<String>,
    /// Every fresh scenario run, in the order run.
    pub scenarios: Vec<ScenarioRecord>,
}

/// The certification's stopping rule over a design's positions in the study's order (round k
/// visits every object's scenario k): an object certified at a look runs no more scenarios;
/// the design stops at the first object given up, and is certified once every object is.
#[derive(Debug, Clone)]
pub struct CertifyRule<'a> {
    plan: &'a CertifyPlan,
    runs: Vec<usize>,
    stays: Vec<usize>,
    decided: Vec<ObjectDecision>,
}

impl<'a> CertifyRule<'a> {
    /// The rule for `objects` objects.
    pub fn new(plan: &'a CertifyPlan, objects: usize) -> Self {
        CertifyRule {
            plan,
            runs: vec![0; objects],
            stays: vec![0; objects],
            decided: vec![ObjectDecision::Open; objects],
        }
    }
    /// Whether scenario k of object o is still needed.
    pub fn needs(&self, o: usize) -> bool {
        !self.stopped() && self.decided[o] == ObjectDecision::Open
    }
    /// The design's certification is decided: an object given up, or every object certified.
    pub fn stopped(&self) -> bool {
        self.decided.contains(&ObjectDecision::GivenUp)
            || self.decided.iter().all(|d| matches!(d, ObjectDecision::Certified(_)))
    }
    /// The next scenario of object `r.object` (its results in their order).
    pub fn push(&mut self, r: &ScenarioRecord) {
        let o = r.object;
        self.runs[o] += 1;
        // an aborted scenario measured nothing: counted as a failure
        self.stays[o] += usize::from(r.stays && !r.aborted());
        self.decided[o] = self.plan.decide(self.stays[o], self.runs[o]);
    }
}

impl Study {
    /// Certify a design that passed stages 0–2 on this study (a certification study: the
    /// fresh stream, K = the plan's last look), its scenarios from `get(o, k)` in the study's
    /// order while the rule needs them.
    pub fn certify(
        &self,
        plan: &CertifyPlan,
        start: &DesignStart,
        mut get: impl FnMut(usize, usize) -> ScenarioRecord,
    ) -> CertificationRecord {
        if let Some(d) = &start.discard {
            return CertificationRecord {
                reason: Some(format!("discarded at stage {}: {}", d.stage(), d.reason(self))),
                objects: self.object_certifications(plan, &[], &CertifyRule::new(plan, self.objects())),
                ..CertificationRecord::default()
            };
        }
        let mut rule = CertifyRule::new(plan, self.objects());
        let mut scen = vec![];
        for (o, k) in self.sequence() {
            if rule.stopped() {
                break;
            }
            if rule.needs(o) {
                let r = get(o, k);
                rule.push(&r);
                scen.push(r);
            }
        }
        self.certification_record(plan, start, scen, &rule)
    }

    /// The record of a certification whose scenarios `scen` ran under `rule`.
    fn certification_record(
        &self,
        plan: &CertifyPlan,
        start: &DesignStart,
        scen: Vec<ScenarioRecord>,
        rule: &CertifyRule<'_>,
    ) -> CertificationRecord {
        let objects = self.object_certifications(plan, &scen, rule);
        let certified = objects.iter().all(|o| o.certified == Some(true));
        let reason = (!certified).then(|| match objects.iter().find(|o| o.certified == Some(false)) {
            Some(o) => format!(
                "object {}: stays in {} of {} fresh scenarios: more failures than P(stay) >= {} at {} % confidence allows (looks {:?})",
                o.name,
                o.stays,
                o.scenarios,
                plan.p_min,
                plan.confidence * 100.0,
                plan.looks
            ),
            None => "not decided".into(),
        });
        let (record, _) = chance_record(self, start, scen.clone());
        let objectives = record.robust.map(|r| r.objectives).unwrap_or_default();
        CertificationRecord { certified, objects, objectives, scenarios_run: scen.len(), reason, scenarios: scen }
    }

    fn object_certifications(
        &self,
        plan: &CertifyPlan,
        scen: &[ScenarioRecord],
        rule: &CertifyRule<'_>,
    ) -> Vec<ObjectCertification> {
        (0..self.objects())
            .map(|o| {
                let mine = scen.iter().filter(|r| r.object == o);
                let runs = mine.clone().count();
                let stays = mine.filter(|r| r.stays && !r.aborted()).count();
                let (certified, look) = match rule.decided[o] {
                    ObjectDecision::Certified(i) => (Some(true), Some(plan.looks[i])),
                    ObjectDecision::GivenUp => (Some(false), None),
                    ObjectDecision::Open => (None, None),
                };
                ObjectCertification {
                    name: self.object_name(o).unwrap_or_default().to_string(),
                    scenarios: runs,
                    stays,
                    p_stay_lower: plan.lower_bound(stays, runs),
                    certified,
                    look,
                }
            })
            .collect()
    }

    /// The last position in the study's order a certification can still need, knowing only
    /// some of its scenarios (`done[j]`: position j's record once it ran): the position of the
    /// first object's failure beyond the last look's allowance among the known results (the
    /// design stops there or earlier). Positions after it are never needed.
    pub fn certify_bound(&self, plan: &CertifyPlan, done: &[Option<ScenarioRecord>]) -> usize {
        let mut fails = vec![0usize; self.objects()];
        for (j, (o, _)) in self.sequence().enumerate() {
            let Some(r) = done.get(j).and_then(Option::as_ref) else { continue };
            if !r.stays || r.aborted() {
                fails[o] += 1;
                if fails[o] > plan.max_failures() {
                    return j;
                }
            }
        }
        self.planned().saturating_sub(1)
    }

    /// Whether position j's object is surely certified from `done` already: every one of its
    /// scenarios up to a look known, and that look certifies it (its later scenarios are not
    /// needed).
    pub fn certified_before(&self, plan: &CertifyPlan, done: &[Option<ScenarioRecord>], o: usize, k: usize) -> bool {
        let at = |k: usize| done.get(k * self.objects() + o).and_then(Option::as_ref);
        let mut stays = 0;
        for kk in 0..k {
            let Some(r) = at(kk) else { return false };
            stays += usize::from(r.stays && !r.aborted());
            if let ObjectDecision::Certified(_) = plan.decide(stays, kk + 1) {
                return true;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(p_min: f64, confidence: f64, looks: &[usize]) -> CertifyPlan {
        CertifyPlan::new(&Certify { enabled: true, confidence, looks: looks.to_vec() }, p_min)
    }

    /// The plan for p_min 0.85 at 95 %: looks at 24 and 48, α split over them:
    /// certified at 24 of 24 or at 46 or more of 48; given up at the third failure.
    #[test]
    fn the_plan_for_0_85_certifies_at_24_of_24_or_46_of_48() {
        let p = plan(0.85, 0.95, &[24, 48]);
        assert_eq!(p.min_stays, vec![24, 46]);
        assert_eq!(p.max_failures(), 2);
        // the thresholds are the binomial tails themselves, computed here independently
        let tail = |s: usize, n: usize, q: f64| -> f64 {
            (s..=n)
                .map(|j| {
                    let c: f64 = (0..j).map(|i| (n - i) as f64 / (i + 1) as f64).product();
                    c * q.powi(j as i32) * (1.0 - q).powi((n - j) as i32)
                })
                .sum()
        };
        assert!(tail(24, 24, 0.85) <= 0.025 && tail(23, 24, 0.85) > 0.025);
        assert!(tail(46, 48, 0.85) <= 0.025 && tail(45, 48, 0.85) > 0.025);
        assert_eq!(p.decide(24, 24), ObjectDecision::Certified(0));
        assert_eq!(p.decide(23, 24), ObjectDecision::Open);
        assert_eq!(p.decide(46, 48), ObjectDecision::Certified(1));
        assert_eq!(p.decide(7, 10), ObjectDecision::GivenUp);
        // the lower bound reaches p_min exactly where the look certifies
        assert!(p.lower_bound(24, 24) >= 0.85 && p.lower_bound(23, 24) < 0.85);
        assert!(p.lower_bound(46, 48) >= 0.85 && p.lower_bound(45, 48) < 0.85);
    }

    /// The test's validity: at P(stay) = p_min (and below) an object is certified with
    /// probability at most α, by the exact operating characteristic and by simulated
    /// Bernoulli outcomes through the rule itself; and it is monotone in P(stay).
    #[test]
    fn an_object_at_p_min_is_certified_at_most_alpha_of_the_time() {
        use rand::{Rng, SeedableRng};
        for (p_min, conf, looks) in [(0.85, 0.95, vec![24, 48]), (0.9, 0.9, vec![22, 44, 66]), (0.7, 0.95, vec![10])] {
            let p = plan(p_min, conf, &looks);
            let alpha = 1.0 - conf;
            assert!(p.probability_certified(p_min) <= alpha, "{looks:?}: {}", p.probability_certified(p_min));
            assert!(p.probability_certified(p_min - 0.05) <= alpha);
            let mut last = 0.0;
            for q in [0.5, 0.7, 0.8, 0.9, 0.95, 0.99, 1.0] {
                let oc = p.probability_certified(q);
                assert!(oc >= last - 1e-15, "monotone");
                last = oc;
            }
            assert!((p.probability_certified(1.0) - 1.0).abs() < 1e-12);
            // Monte Carlo through the rule: 20 000 objects at P = p_min
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
            let n = 20_000;
            let mut certified = 0;
            for _ in 0..n {
                let (mut stays, mut runs) = (0, 0);
                loop {
                    runs += 1;
                    stays += usize::from(rng.random::<f64>() < p_min);
                    match p.decide(stays, runs) {
                        ObjectDecision::Certified(_) => {
                            certified += 1;
                            break;
                        }
                        ObjectDecision::GivenUp => break,
                        ObjectDecision::Open if runs == p.last() => break,
                        ObjectDecision::Open => {}
                    }
                }
            }
            let rate = certified as f64 / n as f64;
            let oc = p.probability_certified(p_min);
            // 4 standard errors of the simulated rate around the exact one
            let se = (oc * (1.0 - oc) / n as f64).sqrt().max(1e-4);
            assert!((rate - oc).abs() < 4.0 * se, "{looks:?}: simulated {rate}, exact {oc}");
            assert!(rate <= alpha + 4.0 * se);
        }
    }

    /// The operating characteristic of the 24/48 plan (prototype figures, to the
    /// printed digits).
    #[test]
    fn the_operating_characteristic_of_24_48() {
        let p = plan(0.85, 0.95, &[24, 48]);
        let oc = [0.80, 0.85, 0.90, 0.95, 0.97, 1.0].map(|q| p.probability_certified(q));
        let want = [0.006, 0.033, 0.16, 0.60, 0.84, 1.00];
        for (got, want) in oc.iter().zip(want) {
            assert!((got - want).abs() < 0.006, "{oc:?}");
        }
    }
}
