//! Events of a simulation (MODEL.md §8.7): their kinds, the crossing rule of each, the
//! test that decides whether to sample inside a step, the root locator on the dense
//! interpolant of a step, and the search for a step's earliest event ([`EventSearch`],
//! root finding as a type, as in diffsol).

/// What an event function watches. Indices name a scene's contacts and fingers (the centred
/// scene: contact 0 proximal, 1 distal; finger 0 only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// Onset or separation of contact `i` (δ_i = 0, with the ε_sep hysteresis of §8.5).
    Contact(u8),
    /// Time to stability: E_ex falls to η U_min after the first contact (§9.4).
    Stability,
    /// The filtered hand force leaves the stability region (§9.3).
    Force,
    /// Finger `i` reaches |sin q13| = 1e-3 (parallel singularity: abort).
    Singular(u8),
    /// The distal stop of finger `i` engages or releases at θ2 = 0 (a kink of the
    /// right-hand side).
    Stop(u8),
}

impl EventKind {
    /// The crossing that triggers this event (`active`: the contact's memory is set; used
    /// by contacts only).
    #[inline]
    pub fn crossing(self, active: bool) -> Crossing {
        match self {
            EventKind::Contact(_) if active => Crossing::Down,
            EventKind::Contact(_) => Crossing::Up,
            EventKind::Force => Crossing::DownNegative,
            EventKind::Stop(_) => Crossing::Either,
            EventKind::Stability | EventKind::Singular(_) => Crossing::Down,
        }
    }

    /// Can this event happen and undo itself inside one step (a contact opening and
    /// closing, the stop engaging and releasing)? Such events are sampled inside a step
    /// where the cubic through the end values and rates may cross (`hermite_may_cross`).
    #[inline]
    pub fn sampled_inside(self) -> bool {
        matches!(self, EventKind::Contact(_) | EventKind::Stop(_))
    }
}

/// How an event function g crosses zero between two values a → b.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crossing {
    /// From ≤ 0 to > 0 (a contact onset).
    Up,
    /// From > 0 to ≤ 0 (a separation, stability, singularity).
    Down,
    /// From ≥ 0 to < 0 (the force margin becoming negative).
    DownNegative,
    /// Either way across 0 (the stop).
    Either,
}

impl Crossing {
    /// Did g cross between a and b?
    #[inline]
    pub fn crossed(self, a: f64, b: f64) -> bool {
        match self {
            Crossing::Up => a <= 0.0 && b > 0.0,
            Crossing::Down => a > 0.0 && b <= 0.0,
            Crossing::DownNegative => a >= 0.0 && b < 0.0,
            Crossing::Either => (a > 0.0) != (b > 0.0),
        }
    }
}

/// The values of a scene's `E` event functions at one state, with their time derivatives
/// where an event is sampled inside a step ([`EventKind::sampled_inside`]; unused otherwise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventValues<const E: usize> {
    /// g_i.
    pub g: [f64; E],
    /// dg_i/dt.
    pub rate: [f64; E],
}

/// The search for the earliest event in a step (t0, t1], given the event functions' values
/// at both ends; it counts the model evaluations the root location makes.
#[derive(Debug, Clone, Copy)]
pub struct EventSearch<const E: usize> {
    kinds: [EventKind; E],
    /// Model evaluations made to locate events (right-hand-side evaluations of the run).
    pub evals: u64,
}

impl<const E: usize> EventSearch<E> {
    /// A search over event functions of these kinds.
    pub fn new(kinds: [EventKind; E]) -> Self {
        EventSearch { kinds, evals: 0 }
    }

    /// The kind of event `k`.
    pub fn kind(&self, k: usize) -> EventKind {
        self.kinds[k]
    }

    /// The earliest event in the step (t0, t1] with event values `g0`, `g1` at its ends,
    /// as (time, index). `crossing(k)`: how event k triggers now (None: not watched);
    /// `values(t)`: the event values on the step's interpolant, `value(k, t)`: event k's
    /// alone, which the root location iterates on (None where the model is undefined).
    /// Events that may open and close inside the step are sampled at four points where the
    /// cubic through the end values and rates may cross.
    pub fn earliest(
        &mut self,
        crossing: impl Fn(usize) -> Option<Crossing>,
        values: impl Fn(f64) -> Option<EventValues<E>>,
        value: impl Fn(usize, f64) -> Option<f64>,
        (t0, g0): (f64, &EventValues<E>),
        (t1, g1): (f64, &EventValues<E>),
    ) -> Option<(f64, usize)> {
        let kinds = self.kinds;
        let evals = &mut self.evals;
        // g_k on the interpolant at t (each evaluation counted)
        let mut at = |k: usize, t: f64| {
            *evals += 1;
            value(k, t)
        };
        let mut best: Option<(f64, usize)> = None;
        let mut sampled = false;
        for k in 0..E {
            let Some(c) = crossing(k) else { continue };
            let (ga, gb) = (g0.g[k], g1.g[k]);
            if c.crossed(ga, gb) {
                let te = locate(c, t0, ga, t1, gb, |t| at(k, t));
                if best.is_none_or(|(tb, _)| te < tb) {
                    best = Some((te, k));
                }
            } else if kinds[k].sampled_inside()
                && !sampled
                && hermite_may_cross(ga, g0.rate[k], gb, g1.rate[k], t1 - t0)
            {
                sampled = true;
                let mut ta = t0;
                let mut gprev = *g0;
                for j in 1..=4 {
                    let tj = t0 + (t1 - t0) * j as f64 / 4.0;
                    let gj = if j == 4 {
                        *g1
                    } else {
                        let Some(v) = values(tj) else { break };
                        v
                    };
                    for kk in 0..E {
                        if !kinds[kk].sampled_inside() {
                            continue;
                        }
                        let Some(c) = crossing(kk) else { continue };
                        let (a, b) = (gprev.g[kk], gj.g[kk]);
                        if c.crossed(a, b) && j < 4 {
                            let te = locate(c, ta, a, tj, b, |t| at(kk, t));
                            if best.is_none_or(|(tb, _)| te < tb) {
                                best = Some((te, kk));
                            }
                        }
                    }
                    if best.is_some_and(|(tb, _)| tb <= tj) {
                        break;
                    }
                    ta = tj;
                    gprev = gj;
                }
            }
        }
        best
    }
}

/// Which end of the bracket the last Illinois step kept.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kept {
    Neither,
    Lower,
    Upper,
}

/// Locate the crossing of g in (ta, tb] by the Illinois method, with g(ta) = ga and
/// g(tb) = gb on either side (`g(t)`: g on the step's dense interpolant; `None` ends the
/// search). Returns the "after" end of the final bracket, so the event is seen as crossed.
pub fn locate(crossing: Crossing, ta: f64, ga: f64, tb: f64, gb: f64, mut g: impl FnMut(f64) -> Option<f64>) -> f64 {
    let (mut a, mut fa, mut b, mut fb) = (ta, ga, tb, gb);
    let mut kept = Kept::Neither;
    for _ in 0..80 {
        if (b - a) <= 1e-14 * b.abs().max(1e-3) {
            break;
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let Some(fc) = g(c) else { break };
        if crossing.crossed(fa, fc) {
            b = c;
            fb = fc;
            if kept == Kept::Lower {
                fa *= 0.5;
            }
            kept = Kept::Lower;
        } else {
            a = c;
            fa = fc;
            if kept == Kept::Upper {
                fb *= 0.5;
            }
            kept = Kept::Upper;
        }
    }
    b
}

/// Can the cubic Hermite through (0, a, da) and (h, b, db) take a value `> 0` (`up`) or
/// `≤ 0` (`!up`) strictly inside the step while both ends are on the other side? Used to
/// decide whether an event function must be sampled inside a step.
pub fn hermite_may_cross(a: f64, da: f64, b: f64, db: f64, h: f64) -> bool {
    // p(s) = h00 a + h10 h da + h01 b + h11 h db on s ∈ [0, 1]; find the extrema of the cubic.
    let (m0, m1) = (h * da, h * db);
    // h00 + h01 = 1 with both in [0, 1], |h10|, |h11| ≤ 4/27: p stays within 4/27 (|m0| + |m1|)
    // of [min(a, b), max(a, b)], so ends farther than that (0.15 > 4/27) on one side cannot
    // cross (most calls: contacts far apart or deep in)
    let reach = 0.15 * (m0.abs() + m1.abs());
    if (a > 0.0 && b > 0.0 && a.min(b) > reach) || (a <= 0.0 && b <= 0.0 && a.max(b) < -reach) {
        return false;
    }
    // p'(s) = 6(a − b)(s² − s) + m0(3s² − 4s + 1) + m1(3s² − 2s) = A s² + B s + C
    let qa = 6.0 * (a - b) + 3.0 * m0 + 3.0 * m1;
    let qb = -6.0 * (a - b) - 4.0 * m0 - 2.0 * m1;
    let qc = m0;
    let p = |s: f64| {
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * a + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * b + (s3 - s2) * m1
    };
    let side = a > 0.0;
    let check = |s: f64| s > 0.0 && s < 1.0 && (p(s) > 0.0) != side;
    if qa.abs() < 1e-300 {
        return qb != 0.0 && check(-qc / qb);
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return false;
    }
    let r = disc.sqrt();
    check((-qb + r) / (2.0 * qa)) || check((-qb - r) / (2.0 * qa))
}

#[cfg(test)]
mod tests {
    use super::hermite_may_cross;
    use rand::{Rng, SeedableRng};

    /// §13 item 3 (a contact that opens and closes inside one step): the test that decides
    /// whether to sample inside a step agrees with brute-force sampling of the same cubic
    /// wherever the excursion is not within rounding of zero.
    #[test]
    fn inner_crossing_test_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (mut crossing, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let h = 10f64.powf(rng.random_range(-8.0..-3.0));
            let a: f64 = rng.random_range(-1e-5..1e-5);
            let b = a.signum() * rng.random_range(1e-9..1e-5);
            let (da, db) = (rng.random_range(-1.0..1.0) * 1e-5 / h, rng.random_range(-1.0..1.0) * 1e-5 / h);
            let p = |s: f64| {
                let (s2, s3) = (s * s, s * s * s);
                (2.0 * s3 - 3.0 * s2 + 1.0) * a
                    + (s3 - 2.0 * s2 + s) * h * da
                    + (-2.0 * s3 + 3.0 * s2) * b
                    + (s3 - s2) * h * db
            };
            // the extreme excursion to the other side, by dense sampling
            let n = 4000;
            let worst = (1..n)
                .map(|i| p(i as f64 / n as f64))
                .map(|v| if a > 0.0 { -v } else { v })
                .fold(f64::NEG_INFINITY, f64::max);
            let scale = a.abs().max(b.abs()) + h * (da.abs() + db.abs());
            if worst.abs() < 1e-6 * scale {
                continue; // tangency: either answer is right
            }
            checked += 1;
            let expect = if a > 0.0 { worst >= 0.0 } else { worst > 0.0 };
            crossing += usize::from(expect);
            assert_eq!(hermite_may_cross(a, da, b, db, h), expect, "a {a:e} da {da:e} b {b:e} db {db:e} h {h:e}");
        }
        assert!(checked > 15_000 && crossing > 300, "{checked} checked, {crossing} crossing");
    }
}
