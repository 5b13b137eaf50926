//! `gripopt export` (docs/export.md): the build sheet against MODEL.md §3.4's nominal numbers
//! and the geometry's own identities, the MJCF's open pose, masses and spring against the
//! finger model, bad input (exit 2, the file or flag named, never a panic), an object placed
//! inside the open finger refused (checked against the open pose's geometry from the build
//! sheet and against `simulate`), and a small run in target/mjcf-check/run whose front
//! design `make test` then exports and simulates with MuJoCo (tools/check_mjcf.py).

use crate::common::{output_text, run_gripopt, scratch, BOTTLE_FILE};
use gripopt::export::{BuildSheet, ExportScene, ExportedDesign};
use gripopt::params::{Design, Problem};
use std::path::{Path, PathBuf};

fn nominal() -> ExportedDesign {
    let p = Problem::load(BOTTLE_FILE).unwrap();
    ExportedDesign::new(&Design::nominal(), &p.scene, ExportScene::centred(), "test").unwrap()
}

fn row(s: &BuildSheet, section: &str, name: &str) -> f64 {
    s.rows.iter().find(|r| r.section == section && r.name == name).unwrap_or_else(|| panic!("{section}.{name}")).value
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// MODEL.md §3.4 in the build sheet's units (mm, degrees, grams).
#[test]
fn build_sheet_holds_model_md_nominal_numbers() {
    let s = nominal().build_sheet();
    let want = [
        ("lengths", "l11", 19.76),
        ("lengths", "l22", 9.0896),
        ("lengths", "l12", 45.419424436),
        ("lengths", "t22", 37.6),
        ("lengths", "k10", 16.093476939),
        ("design", "l_hand", 230.0),
        ("open_pose", "q11", -44.441240127),
        ("open_pose", "q21", 45.558759873),
        ("open_pose", "q12", 106.332636305),
        ("open_pose", "q22", -129.76),
        ("open_pose", "q13", -146.092636305),
        ("closed_pose", "theta1", 57.825595319),
        ("closed_pose", "theta2", 68.174528183),
        ("closed_pose", "k1", 18.947295321),
        ("closed_pose", "k2", 30.452704679),
        ("closed_pose", "q11", -4.104849277),
        ("closed_pose", "q12", 73.927843801),
        ("closed_pose", "q22", -61.585471817),
        ("closed_pose", "q13", -73.582871023),
        ("masses", "m11", 2.141686543805),
        ("masses", "m12", 4.922781889786),
        ("masses", "m21", 5.354216359513),
        ("masses", "m22", 5.060449800387),
        ("masses", "I11", 292.1314701809),
        ("masses", "I12", 3415.875879736),
        ("masses", "I21", 4388.868997281),
        ("masses", "I22", 1979.246277171),
        ("masses", "S22_x", -8.798342151567),
        ("masses", "S22_y", 11.63856653168),
        ("object", "m_c", 1005.310),
        ("assembly", "gamma", 1.0),
        ("assembly", "sigma", 1.0),
    ];
    for (sec, name, v) in want {
        let got = row(&s, sec, name);
        let tol = if name == "m_c" { 1e-6 } else { 1e-9 };
        assert!(rel(got, v) <= tol, "{sec}.{name} = {got}, MODEL.md §3.4: {v}");
    }
}

/// The joint positions close the loop and keep every link's length, at the open and the
/// closed pose; finger 2 is finger 1 mirrored; the closed pose's contact points lie on the
/// object (the phalanx axes at distance R + w from its centre).
#[test]
fn build_sheet_joint_positions_are_a_closed_linkage() {
    let s = nominal().build_sheet();
    let pt = |sec: &str, f: u8, n: &str| {
        [row(&s, sec, &format!("finger{f}_{n}_x")), row(&s, sec, &format!("finger{f}_{n}_y"))]
    };
    let dist = |a: [f64; 2], b: [f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    for sec in ["open_pose", "closed_pose"] {
        for f in [1u8, 2] {
            let (o11, o12, o22, o13, tip) =
                (pt(sec, f, "O11"), pt(sec, f, "O12"), pt(sec, f, "O22"), pt(sec, f, "O13"), pt(sec, f, "tip"));
            for (a, b, l) in
                [(o11, o12, "l11"), (o12, o13, "l12"), (o11, o22, "l21"), (o22, o13, "l22"), (o22, tip, "t22")]
            {
                let want = row(&s, "lengths", l);
                assert!((dist(a, b) - want).abs() < 1e-9, "{sec} finger {f}: {l} = {} mm, sheet {want}", dist(a, b));
            }
        }
        for n in ["O11", "O12", "O22", "O13", "tip"] {
            let (a, b) = (pt(sec, 1, n), pt(sec, 2, n));
            assert!(a[0] == -b[0] && a[1] == b[1], "{sec}.{n}: finger 2 {b:?} is not the mirror of finger 1 {a:?}");
        }
    }
    // closed pose on R = 40 mm: both phalanx axes tangent to the circle of radius R + w at (0, R)
    let c = [0.0, 40.0];
    let (o11, o22, tip) = (pt("closed_pose", 1, "O11"), pt("closed_pose", 1, "O22"), pt("closed_pose", 1, "tip"));
    for (a, b) in [(o11, o22), (o22, tip)] {
        let (ux, uy) = (b[0] - a[0], b[1] - a[1]);
        let d = ((c[0] - a[0]) * uy - (c[1] - a[1]) * ux).abs() / (ux * ux + uy * uy).sqrt();
        assert!((d - 45.0).abs() < 1e-9, "phalanx axis at {d} mm from the object centre, want R + w = 45 mm");
    }
}

/// The MJCF holds the open pose as every hinge's `ref` (qpos0), the stop at θ2 = 0, the
/// spring preload, MODEL.md's masses, and is the same text every time.
#[test]
fn mjcf_holds_the_open_pose_masses_and_torques() {
    let x = nominal();
    let m = x.mjcf();
    assert_eq!(m, nominal().mjcf(), "the export is deterministic");
    assert!(m.starts_with("<?xml") && m.trim_end().ends_with("</mujoco>"), "not one MJCF document");
    assert!(!m.contains("NaN") && !m.contains("inf"), "non-finite numbers");
    let o = x.finger.open;
    for (j, q) in [("q11", o.q11), ("q12", o.q12), ("q21", o.q21), ("q22", o.q22)] {
        for f in ["f1", "f2"] {
            let tag = format!("<joint name=\"{f}_{j}\" type=\"hinge\" axis=\"0 0 1\" ref=\"{q}\"");
            assert!(m.contains(&tag), "missing {tag}");
        }
    }
    let psi = Design::nominal().psi;
    assert!(m.contains(&format!("range=\"{} {}\"", -psi, std::f64::consts::PI)), "stop at q22 = −ψ");
    assert!(m.contains(&format!("biasprm=\"{} 0 0\"", -x.tau_s0)), "spring bias −τ_s0");
    assert!((x.tau_s0 - x.tau_s_min).abs() == 0.0 && x.tau_s0 > 0.0);
    for mass in ["0.002141686543805234", "0.004922781889786219", "0.005354216359513085", "0.005060449800387088"] {
        assert_eq!(m.matches(&format!("mass=\"{mass}\"")).count(), 2, "{mass} on both fingers");
    }
    for q in ["<connect name=\"f1_loop\"", "<connect name=\"f2_loop\"", "<key name=\"grasp\"", "<freejoint"] {
        assert_eq!(m.contains(q), q != "<freejoint", "{q}");
    }
    let free = ExportedDesign::new(&Design::nominal(), &x.scene, ExportScene::free(0.0), "test").unwrap().mjcf();
    for q in ["<freejoint name=\"object_free\"/>", "name=\"palm_object\"", "name=\"ground_object\""] {
        assert!(free.contains(q), "free scene: {q}");
    }
}

/// A design without an open pose is bad input, not a panic.
#[test]
fn an_unbuildable_design_is_an_input_error() {
    let p = Problem::load(BOTTLE_FILE).unwrap();
    let mut d = Design::nominal();
    d.b = 0.02; // k10² < 0
    let e = ExportedDesign::new(&d, &p.scene, ExportScene::centred(), "problem x").unwrap_err();
    assert!(e.is_input() && e.to_string().contains("open pose"), "{e}");
    let o = run_gripopt(&[
        "export",
        BOTTLE_FILE,
        "--design",
        "l21=0.05,b=0.02,t22=0.03,r=0.5,p=0.4,psi_deg=130",
        "--out",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
}

fn bad(args: &[&str], names: &[&str]) {
    let o = run_gripopt(args);
    let t = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
    assert!(!t.contains("panicked"), "{args:?}: {t}");
    for n in names {
        assert!(t.contains(n), "{args:?}: the message must name `{n}`: {t}");
    }
}

/// Bad flags and files: exit 2 with the file or flag named; an existing file is kept
/// unless --force; `--out -` writes to standard output.
#[test]
fn bad_input_is_refused_with_exit_2() {
    let d = scratch("cli");
    let out = d.join("model.xml");
    let o = run_gripopt(&["export", BOTTLE_FILE, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", output_text(&o));
    std::fs::write(&out, "keep me").unwrap();
    bad(&["export", BOTTLE_FILE, "--out", out.to_str().unwrap()], &["model.xml", "--force"]);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "keep me", "an existing file was overwritten");
    let o = run_gripopt(&["export", BOTTLE_FILE, "--out", out.to_str().unwrap(), "--force"]);
    assert!(o.status.success() && std::fs::read_to_string(&out).unwrap().contains("<mujoco"), "{}", output_text(&o));
    let under_file = out.join("x.xml");
    bad(&["export", BOTTLE_FILE, "--out", under_file.to_str().unwrap()], &["x.xml"]);
    bad(&["export", BOTTLE_FILE, "--out", "/nonexistent-gripopt-dir/m.xml"], &["/nonexistent-gripopt-dir"]);
    bad(&["export", BOTTLE_FILE, "--out", d.to_str().unwrap(), "--format", "mjcf"], &["folder"]);
    bad(&["export", BOTTLE_FILE, "--out", d.join("m.txt").to_str().unwrap()], &["--format", "m.txt"]);
    bad(&["export", BOTTLE_FILE, "--out", "-", "--format", "mjfc"], &["mjfc", "--format"]);
    bad(&["export", BOTTLE_FILE, "--out", "-", "--format", "mjcf", "--scene", "fre"], &["fre", "--scene"]);
    bad(&["export", BOTTLE_FILE, "--out", "-", "--format", "json", "--design", "l21=0.05"], &["--design", "b"]);
    bad(&["export", "/nonexistent/problem.toml", "--out", "-", "--format", "json"], &["/nonexistent/problem.toml"]);
    let o = run_gripopt(&["export", BOTTLE_FILE, "--out", "-", "--format", "csv"]);
    assert!(
        o.status.success() && String::from_utf8_lossy(&o.stdout).contains("section,name,value,unit"),
        "{}",
        output_text(&o)
    );
    let o = run_gripopt(&["export", BOTTLE_FILE, "--out", "-", "--format", "json"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON build sheet");
    assert!(rel(j["lengths"]["l12_mm"].as_f64().unwrap(), 45.419424436) < 1e-9, "{j}");
}

/// The object's x in an MJCF (its body's `pos`).
fn object_x(mjcf: &str) -> f64 {
    let tag = "<body name=\"object\" pos=\"";
    let at = mjcf.find(tag).expect("the object body") + tag.len();
    mjcf[at..].split_whitespace().next().unwrap().parse().unwrap()
}

/// `--scene free` on an offset problem stands the object at the problem's x_off, as replay
/// does (docs/scenes.md: `free` without X is the run's x_off); `free:X` and `offset:X` put it
/// at X, `centred` at 0; a bad X is exit 2 naming the flag.
#[test]
fn the_scene_flag_follows_replays_rule() {
    let d = scratch("scene");
    let problem = d.join("offset.toml");
    let src = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let src = src.replacen("kind = \"centred\"", "kind = \"offset\"", 1).replacen("x_off = 0.0 ", "x_off = 0.002 ", 1);
    assert!(src.contains("x_off = 0.002"), "the problem's [scene] changed: fix the test");
    std::fs::write(&problem, src).unwrap();
    let p = problem.to_str().unwrap();
    for (scene, x) in [
        (None, 0.002),
        (Some("free"), 0.002),
        (Some("free:0.001"), 0.001),
        (Some("offset:-0.003"), -0.003),
        (Some("centred"), 0.0),
    ] {
        let mut args = vec!["export", p, "--out", "-", "--format", "mjcf"];
        args.extend(scene.iter().flat_map(|s| ["--scene", *s]));
        let o = run_gripopt(&args);
        assert!(o.status.success(), "{scene:?}: {}", output_text(&o));
        let m = String::from_utf8_lossy(&o.stdout);
        assert_eq!(object_x(&m), x, "{scene:?}: the object's x");
        assert_eq!(m.contains("freejoint"), scene.is_some_and(|s| s.starts_with("free")), "{scene:?}");
    }
    bad(&["export", p, "--out", "-", "--format", "mjcf", "--scene", "free:abc"], &["--scene", "free:abc"]);
    bad(&["export", p, "--out", "-", "--format", "mjcf", "--scene", "free:5"], &["x_off"]);
}

/// A design of a robust problem is exported with the reference [object] only, and a note
/// on stderr says so (as sweep's); a single-object problem has no note.
#[test]
fn a_robust_problems_export_says_it_holds_the_reference_object_only() {
    let kitchen = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");
    assert!(Problem::load(kitchen).unwrap().robust.is_some(), "kitchen.toml is no longer robust: fix the test");
    let o = run_gripopt(&["export", kitchen, "--out", "-", "--format", "json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{}", output_text(&o));
    assert!(err.contains("note:") && err.contains("[robust]") && err.contains("reference [object]"), "{err}");
    let o = run_gripopt(&["export", BOTTLE_FILE, "--out", "-", "--format", "json"]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("[robust]"), "{}", output_text(&o));
}

/// The run of `make test`'s MuJoCo check: a tiny recorded run in target/mjcf-check/run;
/// its front designs export as `RUN_DIR --design ID`, with the run's source named; bad ids
/// and folders are exit 2.
#[test]
fn run_folder_designs_export() {
    let base = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/mjcf-check"));
    std::fs::create_dir_all(&base).unwrap();
    let dir = base.join("run");
    let _ = std::fs::remove_dir_all(&dir);
    crate::common::tiny_run_in(dir.clone(), Path::new(BOTTLE_FILE), 8, 2);
    let id = front_id(&dir);
    let r = dir.to_str().unwrap();
    let out = scratch("run").join("front.xml");
    let o = run_gripopt(&["export", r, "--design", &id, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", output_text(&o));
    let m = std::fs::read_to_string(&out).unwrap();
    assert!(m.contains(&format!("design {id}")) && m.contains("run folder"), "the source is not named");
    bad(&["export", r, "--design", "999999", "--out", "-", "--format", "mjcf"], &["999999"]);
    bad(&["export", r, "--design", "front", "--out", "-", "--format", "mjcf"], &["--design", "front"]);
    bad(&["export", r, "--out", "-", "--format", "mjcf"], &["--design"]);
    let not_a_run = scratch("not-a-run");
    bad(&["export", not_a_run.to_str().unwrap(), "--design", "1", "--out", "-", "--format", "mjcf"], &["problem.toml"]);
    export_never_writes_into_its_run_folder(&dir, &id, &out);
}

/// `--out` inside the source run folder (a shard it reads, run.json, a new file) is refused
/// even with --force (exit 2, the path named), leaving the run's files byte for byte;
/// --force still replaces an earlier export.
fn export_never_writes_into_its_run_folder(dir: &Path, id: &str, earlier: &Path) {
    let r = dir.to_str().unwrap();
    let shard = std::fs::read_dir(dir.join("recording"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "mcap"))
        .expect("a shard");
    for (target, format) in [(shard, "json"), (dir.join("run.json"), "json"), (dir.join("checkpoint.json"), "mjcf")] {
        let before = std::fs::read(&target).unwrap();
        let t = target.to_str().unwrap();
        bad(&["export", r, "--design", id, "--out", t, "--format", format, "--force"], &[t, "run folder"]);
        assert_eq!(std::fs::read(&target).unwrap(), before, "{t} was overwritten by an export");
    }
    // from a problem file, into a run's recording/: refused as well
    let shard = std::fs::read_dir(dir.join("recording")).unwrap().map(|e| e.unwrap().path()).next().unwrap();
    let before = std::fs::read(&shard).unwrap();
    let t = shard.to_str().unwrap();
    bad(&["export", BOTTLE_FILE, "--out", t, "--format", "json", "--force"], &[t, "run folder"]);
    assert_eq!(std::fs::read(&shard).unwrap(), before, "{t} was overwritten by an export");
    let inside = dir.join("design.xml");
    bad(&["export", r, "--design", id, "--out", inside.to_str().unwrap()], &["design.xml", "run folder"]);
    assert!(!inside.exists(), "an export was written into the run folder");
    // through a relative path with `..` that resolves into the folder
    let sneaky = dir.join("recording").join("..").join("run.json");
    bad(&["export", r, "--design", id, "--out", sneaky.to_str().unwrap(), "--force"], &["run folder"]);
    let o = run_gripopt(&["export", r, "--design", id, "--out", earlier.to_str().unwrap(), "--force"]);
    assert!(o.status.success(), "--force must replace an earlier export: {}", output_text(&o));
}

/// The first design id of a run's pareto.csv.
fn front_id(dir: &Path) -> String {
    let text = std::fs::read_to_string(dir.join("pareto.csv")).unwrap();
    let line = text.lines().filter(|l| !l.starts_with('#')).nth(1).expect("a front design");
    line.split(',').next().unwrap().to_string()
}

/// The design of the hostile report (its open finger 1 reaches x = 0.008 m into the object).
const HOSTILE: &str = "l21=0.051584811442040655,b=0.07088732948111638,t22=0.03980884267391382,r=0.21257567978228534,p=0.5996165495350303,psi_deg=109.86029530342392";

/// Finger 1's phalanges at the open pose (segments, m) and the capsule radius w (m), read
/// from the centred build sheet (JSON) of `design`.
fn open_phalanges(design: &str) -> ([[f64; 2]; 3], f64) {
    let o = run_gripopt(&["export", BOTTLE_FILE, "--design", design, "--format", "json", "--out", "-"]);
    assert!(o.status.success(), "{}", output_text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mm = |k: &str| v["open_pose"][k].as_f64().unwrap_or_else(|| panic!("{k}")) * 1e-3;
    let p = |n: &str| [mm(&format!("finger1_{n}_x_mm")), mm(&format!("finger1_{n}_y_mm"))];
    ([p("O11"), p("O22"), p("tip")], v["lengths"]["w_mm"].as_f64().unwrap() * 1e-3)
}

/// The deepest penetration of finger 1's open phalanges (capsules of radius `w`) into the
/// cylinder of radius `r` centred at (x_off, r): R + w − distance (negative when clear).
/// Finger 2 is the mirror image: it meets the object at −x_off as finger 1 at x_off.
fn penetration(seg: &[[f64; 2]; 3], w: f64, r: f64, x_off: f64) -> f64 {
    let c = [x_off, r];
    let mut d_min = f64::INFINITY;
    for k in 0..2 {
        let (a, b) = (seg[k], seg[k + 1]);
        let ab = [b[0] - a[0], b[1] - a[1]];
        let t = (((c[0] - a[0]) * ab[0] + (c[1] - a[1]) * ab[1]) / (ab[0] * ab[0] + ab[1] * ab[1])).clamp(0.0, 1.0);
        let d = (c[0] - a[0] - t * ab[0]).hypot(c[1] - a[1] - t * ab[1]);
        d_min = d_min.min(d);
    }
    r + w - d_min
}

/// The number after `pat` in `text` (up to the next space).
fn number_after(text: &str, pat: &str) -> f64 {
    let at = text.find(pat).unwrap_or_else(|| panic!("`{pat}` in: {text}")) + pat.len();
    text[at..].split_whitespace().next().unwrap().parse().unwrap_or_else(|_| panic!("a number after `{pat}`: {text}"))
}

const R: f64 = 0.040; // bottle-1l's object radius (m)

/// The hostile report's case: `export --scene offset:0.008` (and `free:0.008`, `free:-0.008`)
/// exits 2 and writes nothing, naming --scene, the offset and a depth that the build sheet's
/// geometry gives independently; `simulate` of the free scene there stops at t = 0 for the
/// same reason. Without the check the export wrote the model with exit 0.
/// Origin: hostile pass of session 35, export of an object placed inside an open finger.
#[test]
fn export_refuses_an_object_placed_inside_an_open_finger() {
    let d = scratch("refuse");
    let (seg, w) = open_phalanges(HOSTILE);
    let depth = penetration(&seg, w, R, 0.008);
    assert!(depth > 1e-3, "the case penetrates by {depth} m");
    for scene in ["offset:0.008", "free:0.008", "free:-0.008"] {
        let out = d.join("o.xml");
        let o = run_gripopt(&[
            "export",
            BOTTLE_FILE,
            "--design",
            HOSTILE,
            "--scene",
            scene,
            "--out",
            out.to_str().unwrap(),
        ]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{scene}: {text}");
        assert!(!out.exists(), "{scene}: nothing written");
        assert!(text.contains(&format!("--scene {scene}")) && text.contains("penetrates"), "{text}");
        let finger = if scene.contains('-') { "finger 2" } else { "finger 1" };
        assert!(text.contains(finger), "{text}");
        let said = number_after(&text, "penetrates it by ") * 1e-3;
        assert!((said - depth).abs() < 1e-3 * depth, "{scene}: said {said} m, geometry {depth} m");
    }
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--design", HOSTILE, "--scene", "free:0.008"]);
    assert!(output_text(&o).contains("open finger penetrates the object at t = 0"), "{}", output_text(&o));
}

/// The offset the refusal names as the last clear one is the geometry's (bisected here on
/// the build sheet's open pose), and the simulation agrees on both sides of it: the nominal
/// design exports and simulates at 0.99 of it, and is refused by both at 1.01 of it (at
/// 0.0045 m it already overlaps by about 0.2 mm).
/// Origin: hostile pass of session 35, export of an object placed inside an open finger.
#[test]
fn the_last_clear_offset_is_where_the_simulation_starts() {
    let d = scratch("boundary");
    let nominal = "l21=0.0494,b=0.056,t22=0.0376,r=0.46,p=0.4,psi_deg=129.76";
    let (seg, w) = open_phalanges(nominal);
    let (mut lo, mut hi) = (0.0, 0.0045);
    assert!(penetration(&seg, w, R, lo) < 0.0 && penetration(&seg, w, R, hi) > 1e-4);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if penetration(&seg, w, R, mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let out = d.join("n.xml");
    let o = run_gripopt(&["export", BOTTLE_FILE, "--scene", "free:0.0045", "--out", out.to_str().unwrap()]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    let said = number_after(&text, "|x_off| = ") * 1e-3;
    assert!((said - lo).abs() < 1e-6, "said {said} m, geometry {lo} m");
    let inside = format!("free:{}", 1.01 * lo);
    let clear = format!("free:{}", 0.99 * lo);
    let o = run_gripopt(&["export", BOTTLE_FILE, "--scene", &clear, "--out", out.to_str().unwrap()]);
    assert!(o.status.success() && out.exists(), "{}", output_text(&o));
    let o = run_gripopt(&["export", BOTTLE_FILE, "--scene", &inside, "--format", "mjcf", "--out", "-"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(o.stdout.is_empty(), "no model on stdout");
    let starts = |scene: &str| {
        let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", scene]);
        !output_text(&o).contains("open finger penetrates the object at t = 0")
    };
    assert!(starts(&clear), "simulate {clear} starts");
    assert!(!starts(&inside), "simulate {inside} stops at t = 0");
}

/// `--scene free:1e-320` (a subnormal offset within range) is named compactly in the "wrote"
/// line and the model's header, not with 320 digits.
/// Origin: hostile pass of session 35, export of an object placed inside an open finger.
#[test]
fn a_tiny_offset_is_printed_compactly() {
    let d = scratch("tiny");
    let out = d.join("f.xml");
    let o = run_gripopt(&["export", BOTTLE_FILE, "--scene", "free:1e-320", "--out", out.to_str().unwrap()]);
    let text = output_text(&o);
    assert!(o.status.success(), "{text}");
    let wrote = text.lines().find(|l| l.starts_with("wrote ")).expect("a wrote line");
    assert!(wrote.contains("scene free:1e-320") && wrote.len() < 300, "{wrote}");
    let model = std::fs::read_to_string(&out).unwrap();
    assert!(model.contains("<mujoco model=\"gripopt free:1e-320\">"), "{}", &model[..model.len().min(2000)]);
    assert!(!model.contains("0000000000000000000000"), "no long run of digits");
}

/// `--design l21=5e-324,…`: l21 is positive, but l11 = p·l21 underflows to 0; export's error
/// and evaluate's warning say which length, its value and why, not "a length is not positive".
/// Origin: hostile pass of session 35, export of an object placed inside an open finger.
#[test]
fn a_subnormal_length_is_named_with_its_value() {
    let design = "l21=5e-324,b=0.056,t22=0.0376,r=0.46,p=0.4,psi_deg=129.76";
    let o = run_gripopt(&["export", BOTTLE_FILE, "--design", design, "--format", "mjcf", "--out", "-"]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    for want in ["l11 = p·l21 = 0.4 × 5e-324 m = 0 m", "underflows to 0", "l21 = 5e-324 is a subnormal number"] {
        assert!(text.contains(want), "`{want}` in: {text}");
    }
    let o = run_gripopt(&["evaluate", BOTTLE_FILE, "--design", design]);
    let text = output_text(&o);
    assert!(o.status.success(), "{text}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("l11 = p·l21 = 0.4 × 5e-324 m = 0 m"), "{text}");
    // a negative given length is named as such
    let o =
        run_gripopt(&["evaluate", BOTTLE_FILE, "--design", "l21=0.05,b=-0.056,t22=0.0376,r=0.46,p=0.4,psi_deg=129.76"]);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("b = -0.056 m is not a positive length"),
        "{}",
        output_text(&o)
    );
}

/// A run folder whose problem.toml was deleted (run.json still there): export says the
/// problem file is missing and how to restore it, not "not a run folder".
/// Origin: hostile pass of session 35, export of an object placed inside an open finger.
#[test]
fn export_of_a_run_without_its_problem_file_says_what_is_missing() {
    let d = scratch("no-problem");
    let run = d.join("run");
    let o = run_gripopt(&["optimise", BOTTLE_FILE, "--out", run.to_str().unwrap(), "--pop", "4", "--generations", "1"]);
    assert!(o.status.success(), "{}", output_text(&o));
    std::fs::remove_file(run.join("problem.toml")).unwrap();
    let o =
        run_gripopt(&["export", run.to_str().unwrap(), "--design", "1", "--out", d.join("e.xml").to_str().unwrap()]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains("problem.toml is missing from the run folder (run.json is there): restore it"), "{text}");
    assert!(text.contains("bottle-1l.toml") && !text.contains("not a run folder"), "{text}");
    assert!(!d.join("e.xml").exists());
}

/// An object too large for the open hand (bottle-1l with R = 70 mm; the open pose is set by
/// `hand.r_open`, not by R) penetrates it even centred: refused in every format, the depth
/// the build sheet's open pose gives for R = 70 mm.
/// Origin: hostile pass of session 35, export of an object placed inside an open finger.
#[test]
fn an_object_too_large_for_the_open_hand_is_refused_even_centred() {
    let d = scratch("large");
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap().replacen("radius = 0.040 ", "radius = 0.070 ", 1);
    assert!(text.contains("radius = 0.070 "));
    let problem = d.join("large.toml");
    std::fs::write(&problem, text).unwrap();
    let (seg, w) = open_phalanges("l21=0.0494,b=0.056,t22=0.0376,r=0.46,p=0.4,psi_deg=129.76");
    let depth = penetration(&seg, w, 0.070, 0.0);
    assert!(depth > 1e-3, "{depth}");
    for format in ["mjcf", "json", "csv"] {
        let o = run_gripopt(&["export", problem.to_str().unwrap(), "--format", format, "--out", "-"]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{format}: {text}");
        assert!(o.stdout.is_empty() && text.contains("even centred"), "{format}: {text}");
        assert!(text.contains("the problem's [scene] (centred"), "{text}");
        let said = number_after(&text, "penetrates it by ") * 1e-3;
        assert!((said - depth).abs() < 1e-3 * depth, "said {said} m, geometry {depth} m");
    }
}

/// `export --format mjcf --out hand.json` wrote XML under a `.json` name: a format that an
/// extension contradicts is refused naming both; a name whose extension says nothing, or
/// agrees, is written.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn export_refuses_a_format_its_file_name_contradicts() {
    let dir = scratch("format-by-extension");
    let out = |name: &str| dir.join(name).display().to_string();
    let o = run_gripopt(&["export", BOTTLE_FILE, "--format", "mjcf", "--out", &out("hand.json")]);
    let e = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("hand.json") && e.contains("says json") && e.contains("--format is mjcf"), "{e}");
    assert!(!dir.join("hand.json").exists());
    for (format, name) in [("mjcf", "hand.xml"), ("mjcf", "hand.model"), ("json", "sheet.json"), ("csv", "sheet.csv")] {
        let o = run_gripopt(&["export", BOTTLE_FILE, "--format", format, "--out", &out(name)]);
        assert_eq!(o.status.code(), Some(0), "{format} {name}: {}", output_text(&o));
        assert!(dir.join(name).exists(), "{name}");
    }
}
