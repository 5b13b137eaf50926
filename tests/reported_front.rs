//! The front a run reports (pareto.csv, `gripopt show`, `verify`'s designs, front.mcap):
//! the best non-dominated designs of the run's archive, at most the population size, chosen
//! by hypervolume (docs/outputs.md "pareto.csv, the reported front"), and history.csv's
//! `pareto_hypervolume`, checked against independent hypervolumes of the CSVs' objectives.
use gripopt::run::{optimise, Checkpoint, GripperInfo, RunSpec};
use std::path::{Path, PathBuf};

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The data lines of a CSV view (no `#` lines, no header).
fn rows(p: &Path) -> Vec<String> {
    read(p).lines().filter(|l| !l.starts_with('#')).skip(1).map(str::to_string).collect()
}

/// A run of bottle-1l with population `pop`, nothing recorded.
fn run(name: &str, pop: usize, generations: u64) -> PathBuf {
    let d = crate::common::scratch(name);
    let spec = RunSpec {
        pop,
        record: gripopt::record::RecordOptions::none(),
        ..crate::common::bottle_spec(&d, generations, 5, 1)
    };
    optimise(&spec).unwrap();
    d
}

/// The hypervolume of `points` (minimisation) below the reference point `r`, by
/// inclusion–exclusion over every subset: Σ over non-empty subsets S of (−1)^(|S|+1) ·
/// vol(box of the componentwise maximum of S), independent of the library's slicing.
fn inclusion_exclusion(points: &[Vec<f64>], r: &[f64]) -> f64 {
    let pts: Vec<&Vec<f64>> = points.iter().filter(|p| p.iter().zip(r).all(|(a, b)| a < b)).collect();
    assert!(pts.len() <= 16, "inclusion–exclusion of {} points", pts.len());
    let mut total = 0.0;
    for mask in 1u32..(1 << pts.len()) {
        let mut corner = vec![f64::NEG_INFINITY; r.len()];
        for (k, p) in pts.iter().enumerate().filter(|(k, _)| mask & (1 << k) != 0) {
            let _ = k;
            for (c, v) in corner.iter_mut().zip(p.iter()) {
                *c = c.max(*v);
            }
        }
        let vol: f64 = corner.iter().zip(r).map(|(a, b)| b - a).product();
        total += if mask.count_ones() % 2 == 1 { vol } else { -vol };
    }
    total
}

/// The normalised minimisation objectives of a pareto.csv or archive.csv row (run.json's
/// ideal and reference points; a design not form closed: max_offset −Δ_off, outside).
fn normalised(dir: &Path, file: &str) -> Vec<Vec<f64>> {
    let info: serde_json::Value = serde_json::from_str(&read(&dir.join("run.json"))).unwrap();
    let v =
        |k: &str| -> Vec<f64> { info["settings"][k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect() };
    let (ideal, reference) = (v("hv_ideal"), v("hv_ref"));
    let mut r = csv::ReaderBuilder::new().comment(Some(b'#')).from_path(dir.join(file)).unwrap();
    let header = r.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (o, a, m, t) = (col("max_offset"), col("alpha"), col("mean_force"), col("t_stab"));
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            let num = |k: usize| rec[k].parse::<f64>().ok();
            let f = [-num(o).unwrap_or(-2.5e-4), num(a).unwrap(), -num(m).unwrap(), num(t).unwrap()];
            f.iter().enumerate().map(|(k, x)| (x - ideal[k]) / (reference[k] - ideal[k])).collect()
        })
        .collect()
}

/// Issue 42: a pop-6 run whose archive outgrows six designs: pareto.csv holds six of archive.csv's
/// rows (the same lines but `rank`), its hypervolume (history.csv's `pareto_hypervolume`, checked by
/// inclusion–exclusion from the CSV's objectives) lies between the population's and the
/// archive's and is the best of every six-design subset's but for at most the greedy's
/// bound; while the archive fits, pareto.csv is archive.csv.
#[test]
fn pareto_csv_is_the_best_of_the_archive_at_most_the_population_size() {
    let d = run("cap", 6, 12);
    let (front, archive) = (rows(&d.join("pareto.csv")), rows(&d.join("archive.csv")));
    assert!(archive.len() > 6, "the archive outgrew the population ({} designs): pick another seed", archive.len());
    assert_eq!(front.len(), 6);
    // the same cells but `rank` (pareto.csv 0, archive.csv empty)
    let unranked = |l: &String| l.replacen(",0,", ",,", 1);
    assert!(front.iter().all(|l| archive.contains(&unranked(l))), "every pareto.csv row is an archive.csv row");
    let hist = rows(&d.join("history.csv"));
    let last: Vec<&str> = hist.last().unwrap().split(',').collect();
    let (pop_hv, archive_hv, pareto_hv): (f64, f64, f64) =
        (last[3].parse().unwrap(), last[4].parse().unwrap(), last[5].parse().unwrap());
    let r = [1.0; 4];
    let ours = inclusion_exclusion(&normalised(&d, "pareto.csv"), &r);
    assert!((ours - pareto_hv).abs() <= 1e-12, "history's {pareto_hv} vs inclusion–exclusion {ours}");
    assert!(pareto_hv >= pop_hv - 1e-15 && pareto_hv <= archive_hv + 1e-15, "{pop_hv} ≤ {pareto_hv} ≤ {archive_hv}");
    // against the best six-design subset of the archive (all of them, by brute force)
    let all = normalised(&d, "archive.csv");
    let inside: Vec<Vec<f64>> = all.into_iter().filter(|p| p.iter().all(|v| *v < 1.0)).collect();
    if inside.len() <= 18 {
        let mut best = 0.0f64;
        for mask in 0u32..(1 << inside.len()) {
            if mask.count_ones() as usize == 6.min(inside.len()) {
                let sub: Vec<Vec<f64>> =
                    inside.iter().enumerate().filter(|(k, _)| mask & (1 << k) != 0).map(|(_, p)| p.clone()).collect();
                best = best.max(inclusion_exclusion(&sub, &r));
            }
        }
        assert!(pareto_hv >= (1.0 - (-1.0f64).exp()) * best - 1e-15, "{pareto_hv} against the best subset's {best}");
    }
    // the first generations, while the archive fitted: pareto_hypervolume = archive_hypervolume
    let first: Vec<&str> = hist[0].split(',').collect();
    assert_eq!(first[4], first[5], "generation 1: {}", hist[0]);
}

/// Issue 42: `show`'s front (the checkpoint's designs) and `verify`'s designs are
/// pareto.csv's.
#[test]
fn show_and_verify_report_pareto_csvs_designs() {
    let d = run("views", 6, 12);
    let folder = gripopt::RunFolder::open(&d).unwrap();
    let tables = folder.checkpoint_tables().unwrap().unwrap();
    let ids = |rows: &[gripopt::run::DesignRow]| rows.iter().map(|r| r.id).collect::<Vec<_>>();
    assert_eq!(ids(&tables.front), ids(&folder.front().unwrap()));
    assert!(folder.view_differs("pareto.csv", &tables.front, tables.generation).unwrap().is_none());
    let cp = Checkpoint::<GripperInfo>::load(&d.join("checkpoint.json")).unwrap();
    let verified: Vec<u64> =
        gripopt::run::checkpoint_designs(&cp, false, &d.join("checkpoint.json")).unwrap().iter().map(|v| v.0).collect();
    assert_eq!(verified, ids(&tables.front));
    assert!(tables.archive.len() > tables.front.len());
}

/// Issue 42: a history.csv of a gripopt before issue 42 (no `pareto_hypervolume`, here
/// session 36's) still reads, the column empty.
#[test]
fn an_old_history_csv_reads_without_pareto_hypervolume() {
    let fixture = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/checkpoint-s36/radau5"));
    assert!(!read(&fixture.join("history.csv")).contains("pareto_hypervolume"));
    let h = gripopt::RunFolder::open(&fixture).unwrap().history().unwrap();
    assert!(!h.is_empty() && h.iter().all(|r| r.pareto_hypervolume.is_none()));
}

/// Issue 42: a checkpoint whose reported front names a design the archive does not hold, or
/// more designs than the population has, is refused naming the field (never reported
/// short or misattributed).
#[test]
fn a_front_naming_designs_outside_the_archive_is_refused() {
    let d = run("edited", 6, 12);
    let path = d.join("checkpoint.json");
    let original: serde_json::Value = serde_json::from_str(&read(&path)).unwrap();
    let ids: Vec<u64> = original["archive"]["front"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    assert!(!ids.is_empty());
    let members: Vec<u64> =
        original["archive"]["members"].as_array().unwrap().iter().map(|m| m["id"].as_u64().unwrap()).collect();
    let absent = (1..).find(|id| !members.contains(id)).unwrap();
    let mut seven = members.clone();
    seven.resize(7, 0);
    for (front, why) in [
        (vec![absent], format!("design id {absent} is not in `archive.members`")),
        (ids.iter().rev().copied().collect::<Vec<_>>(), "not ascending".to_string()),
        (seven, "more than the population's 6".to_string()),
    ] {
        if front.len() < 2 && why.contains("ascending") {
            continue;
        }
        let mut v = original.clone();
        v["archive"]["front"] = serde_json::json!(front);
        std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
        let e = Checkpoint::<GripperInfo>::load(&path).unwrap_err().to_string();
        assert!(e.contains("archive.front") && e.contains(&why), "{why}: {e}");
    }
}
