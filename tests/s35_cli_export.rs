//! `gripopt export` of a scene whose object starts inside an open finger (an offset or free
//! object placed too far off centre): refused, as the simulation refuses to start there,
//! checked against the open pose's geometry from the build sheet (capsules of radius w
//! around O11–O22 and O22–tip against the cylinder of radius R) and against `simulate`.

use crate::common::{output_text, run_gripopt, BOTTLE_FILE};
use std::path::PathBuf;

/// The design of the hostile report (its open finger 1 reaches x = 0.008 m into the object).
const HOSTILE: &str = "l21=0.051584811442040655,b=0.07088732948111638,t22=0.03980884267391382,r=0.21257567978228534,p=0.5996165495350303,psi_deg=109.86029530342392";

fn scratch(name: &str) -> PathBuf {
    crate::common::scratch_dir("s35-cli-export", name)
}

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
