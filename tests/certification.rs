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

/// The ids of a design table's rows (`#` lines and the column names skipped).
fn table_ids(path: &std::path::Path) -> Vec<u64> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect()
}

/// The data lines of a design table (its `#` lines dropped: the title differs by file).
fn table_data(path: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().filter(|l| !l.starts_with('#')).map(String::from).collect()
}

/// A robust run ends with its certification stage: pareto.csv holds exactly the certified
/// front that certification.json names (each of its designs certified, mutually
/// non-dominated by the fresh objectives the row shows), search_pareto.csv the front that
/// the same run without certification reports as pareto.csv, `show` takes the certified
/// front from the checkpoint without calling the view different; the stage gives the same
/// bytes at 1 and 2 threads and when the finished run is resumed (as after a kill during
/// the stage).
#[test]
fn a_robust_run_reports_its_certified_front() {
    use crate::robust::{robust_text, spec, tmp};
    let dir = tmp("certified-run");
    std::fs::create_dir_all(&dir).unwrap();
    let (file, off) = (dir.join("robust.toml"), dir.join("off.toml"));
    std::fs::write(&file, robust_text("")).unwrap();
    std::fs::write(&off, robust_text("[robust.certify]\nenabled = false\n")).unwrap();
    let runs = [dir.join("t1"), dir.join("t2"), dir.join("off")];
    let s1 = gripopt::run::optimise(&spec(&file, &runs[0], 1)).unwrap();
    gripopt::run::optimise(&spec(&file, &runs[1], 2)).unwrap();
    let s_off = gripopt::run::optimise(&spec(&off, &runs[2], 1)).unwrap();
    assert!(s_off.certification.is_none() && !runs[2].join("certification.json").exists());
    let c = s1.certification.expect("a robust run with p_min 0.5 certifies");
    let cert: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(runs[0].join("certification.json")).unwrap()).unwrap();
    let front: Vec<u64> = cert["front"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    assert_eq!(front, c.front);
    assert!(c.tested > 0 && !front.is_empty(), "the small problem certifies some design: {c:?}");
    assert_eq!(table_ids(&runs[0].join("pareto.csv")), front);
    for id in &front {
        assert_eq!(cert["designs"][id.to_string()]["certified"], true, "design {id}");
    }
    // the fresh objectives the rows show are certification.json's, mutually non-dominated
    let rows = gripopt::run::RunFolder::open(&runs[0]).unwrap().front().unwrap();
    let crit = robust_problem().scene.criteria;
    let f: Vec<[f64; 4]> = rows
        .iter()
        .map(|r| {
            let o = &cert["designs"][r.id.to_string()]["objectives"];
            let v = |k: &str| o[k].as_f64().unwrap_or(f64::NAN);
            let want = [v("max_offset"), v("alpha"), v("mean_force"), v("t_stab")];
            let got = [r.max_offset, r.alpha, r.mean_force, r.t_stab];
            assert_eq!(want.map(f64::to_bits), got.map(|x| x.unwrap_or(f64::NAN).to_bits()), "design {}", r.id);
            minimised(got, &crit)
        })
        .collect();
    let dominates = |a: &[f64; 4], b: &[f64; 4]| a.iter().zip(b).all(|(x, y)| x <= y) && a != b;
    assert!(f.iter().all(|a| f.iter().all(|b| !dominates(a, b))));
    // the search's front is what pareto.csv is without certification
    assert_eq!(table_data(&runs[0].join("search_pareto.csv")), table_data(&runs[2].join("pareto.csv")));
    // threads, and a resume of the finished run, give the same bytes
    let bytes = |d: &std::path::Path| {
        ["pareto.csv", "search_pareto.csv", "certification.json"].map(|f| std::fs::read(d.join(f)).unwrap())
    };
    assert_eq!(bytes(&runs[0]), bytes(&runs[1]));
    let before = bytes(&runs[0]);
    std::fs::remove_file(runs[0].join("certification.json")).unwrap();
    gripopt::run::resume(&runs[0], None, false, Some(2)).unwrap();
    assert_eq!(bytes(&runs[0]), before, "the stage again after a resume: the same bytes");
    // show: the certified front from the checkpoint, no view called different
    let o = crate::common::run_gripopt(&["show", runs[0].to_str().unwrap()]);
    let said = crate::common::output_text(&o);
    assert_eq!(o.status.code(), Some(0), "{said}");
    assert!(!said.contains("does not hold"), "{said}");
}
