//! Certification of a robust run's front on fresh scenarios (issue 41, docs/robust.md
//! "Certification"): the stage's result against an independent recomputation (each design's
//! fresh scenarios run one by one in the test, the sequential rule and its thresholds written
//! here from the binomial tails), its front against the definition (the non-dominated set of
//! the certified designs by their fresh objectives), and its independence of the thread count.

use crate::robust::robust_problem;
use gripopt::eval::{minimised, EvalOptions, Study};
use gripopt::optim::{Individual, MooProblem};
use gripopt::params::{Design, STREAM_CERTIFY, STREAM_OPTIMISE};
use gripopt::run::{certify_front, CertifiedFront, GripperInfo, GripperProblem};
use rand::SeedableRng;

/// Feasible designs of the small robust problem (random draws, evaluated as a run does).
fn candidates(gp: &GripperProblem, n: usize) -> Vec<Individual<GripperInfo>> {
    let p = &gp.problem;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut out = vec![];
    let mut id = 0;
    while out.len() < n && id < 400 {
        let x = p.bounds.sample(&mut rng).to_array().to_vec();
        let eval = gp.evaluate(&x);
        if eval.cv.is_feasible() {
            out.push(Individual { id, generation: 1, x, eval });
        }
        id += 1;
    }
    assert!(out.len() >= 4, "the small robust problem has feasible designs");
    out
}

/// The fewest stays of n that reject H₀: P(stay) < p at level a: P(S ≥ s | n, p) ≤ a.
fn threshold(n: usize, p: f64, a: f64) -> usize {
    let pmf = |j: usize| {
        let c: f64 = (0..j).map(|i| (n - i) as f64 / (i + 1) as f64).product();
        c * p.powi(j as i32) * (1.0 - p).powi((n - j) as i32)
    };
    (0..=n).find(|&s| (s..=n).map(pmf).sum::<f64>() <= a).unwrap_or(n + 1)
}

fn certified(gp: &GripperProblem, threads: usize, c: &[Individual<GripperInfo>]) -> CertifiedFront {
    let refs: Vec<&Individual<GripperInfo>> = c.iter().collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| certify_front(gp, &refs))
}

#[test]
fn a_front_is_certified_as_the_test_defines_whatever_the_threads() {
    let p = robust_problem();
    let r = p.robust.clone().unwrap();
    // the default plan of p_min 0.5 at 95 %: n1 = ⌈ln 0.025 / ln 0.5⌉ = 6, then 12
    assert_eq!(r.certify.looks, vec![6, 12]);
    let gp = GripperProblem::new(p.clone());
    let c = candidates(&gp, 6);
    let one = certified(&gp, 1, &c);
    assert_eq!(one, certified(&gp, 2, &c), "the same certification at 1 and 2 threads");
    assert!(!one.records.is_empty());

    // every tested design, recomputed: its fresh scenarios one by one, the rule written here
    let a = 0.05 / 2.0;
    let need = [threshold(6, 0.5, a), threshold(12, 0.5, a)];
    let max_fail = 12 - need[1];
    let study = Study::drawn(&p, &r, STREAM_CERTIFY, 12, true);
    let search = Study::drawn(&p, &r, STREAM_OPTIMISE, 2, true);
    assert_ne!(study.scenario(0, 0).scenario.values, search.scenario(0, 0).scenario.values, "a fresh stream");
    let opts = EvalOptions::full(&p);
    for (id, rec) in &one.records {
        let ind = c.iter().find(|i| i.id == *id).unwrap();
        let x = Design::from_array(ind.x.as_slice().try_into().unwrap());
        let st = study.start(&x);
        let (mut stays, mut runs, mut open, mut given_up) = ([0usize; 2], [0usize; 2], [true; 2], false);
        'rounds: for k in 0..12 {
            for o in 0..2 {
                if !open[o] {
                    continue;
                }
                let s = study.run_scenario(&st, o, k, &opts, &mut ()).0;
                runs[o] += 1;
                stays[o] += usize::from(s.stays && !s.aborted());
                if runs[o] - stays[o] > max_fail {
                    given_up = true;
                    break 'rounds;
                }
                if (runs[o] == 6 && stays[o] >= need[0]) || (runs[o] == 12 && stays[o] >= need[1]) {
                    open[o] = false;
                }
            }
            if open == [false, false] {
                break;
            }
        }
        assert_eq!(rec.certified, !given_up && open == [false, false], "design {id}");
        for o in 0..2 {
            assert_eq!((rec.objects[o].stays, rec.objects[o].scenarios), (stays[o], runs[o]), "design {id} object {o}");
        }
        assert_eq!(rec.scenarios_run, runs[0] + runs[1]);
    }

    // the front: certified, mutually non-dominated by the fresh objectives, and every other
    // certified design dominated by one of it
    let crit = &p.scene.criteria;
    let f = |id: &u64| minimised(one.records[id].objectives.to_array(), crit);
    let dominates = |a: [f64; 4], b: [f64; 4]| a.iter().zip(&b).all(|(x, y)| x <= y) && a != b;
    for id in &one.front {
        assert!(one.records[id].certified);
        assert!(one.front.iter().all(|o| !dominates(f(o), f(id))));
    }
    for (id, rec) in &one.records {
        if rec.certified && !one.front.contains(id) {
            assert!(one.front.iter().any(|o| dominates(f(o), f(id))), "design {id}");
        }
    }
}
