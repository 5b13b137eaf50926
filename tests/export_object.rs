//! `gripopt export --object NAME` (docs/export.md): a design of a robust problem handed over
//! on one of its `[[robust.objects]]`. The MJCF and the build sheet carry that object's
//! radius, length, grasp height, mass and grip torque as the problem file writes them
//! (computed here from the file's numbers, not from gripopt's output), the spring stays sized
//! at `[hand] tau` (a spring is hardware, as in the robust evaluation), and bad uses of the
//! flag are refused with exit 2, naming it and the known objects.

use crate::common::{output_text, run_gripopt, scratch, BOTTLE_FILE};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

const KITCHEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");

/// kitchen.toml with the can gripped at τ = 0.4 N·m (the hand's τ stays 0.5): the can's
/// block as the file writes it, so that the test fails if the shipped file changes under it.
fn kitchen_with_can_at(dir: &Path, tau: &str) -> PathBuf {
    let text = std::fs::read_to_string(KITCHEN).unwrap();
    let can = "name = \"can\"             # as can.toml: a 330 ml can, 0.34 kg\nradius = 0.030\nlength = 0.115\ndensity = 1050.0\ngrasp_height = 0.040\ntau = 0.5\n";
    assert!(text.contains(can), "problems/kitchen.toml's can block changed: update this test");
    let file = dir.join("kitchen-can-tau.toml");
    std::fs::write(&file, text.replacen(can, &can.replace("tau = 0.5", &format!("tau = {tau}")), 1)).unwrap();
    file
}

/// The value of attribute `attr` of the first element `<tag` whose text contains `key`.
fn attr(xml: &str, tag: &str, key: &str, attr: &str) -> String {
    let el = xml
        .split('<')
        .find(|e| e.starts_with(tag) && e.contains(key))
        .unwrap_or_else(|| panic!("no <{tag} … {key}> in the MJCF"));
    let start = el.find(&format!("{attr}=\"")).unwrap_or_else(|| panic!("<{tag} {key}>: no {attr}")) + attr.len() + 2;
    el[start..].split('"').next().unwrap().to_string()
}

fn nums(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|v| v.parse().unwrap()).collect()
}

fn export(args: &[&str]) -> String {
    let o = run_gripopt(args);
    assert!(o.status.success(), "{args:?}: {}", output_text(&o));
    String::from_utf8(o.stdout).unwrap()
}

fn close(got: f64, want: f64, what: &str) {
    assert!((got - want).abs() <= 1e-12 * want.abs().max(1e-3), "{what}: {got}, the problem file says {want}");
}

/// `--object can` exports the can of the problem file (R 30 mm, L 115 mm, ρ 1050 kg/m³, h_c
/// 40 mm, τ 0.4 N·m): the MuJoCo body's mass ρ π R² L, its cylinder, its place on the ground,
/// the motor torque of the keyframe; the reference export keeps the 1 l bottle. The spring
/// preload is the reference export's (sized at [hand] tau = 0.5 N·m, not at the can's 0.4:
/// τ_s^min is proportional to τ, so a resized spring would be 0.8 times it).
#[test]
fn an_object_export_carries_that_objects_cylinder_mass_and_torque() {
    let d = scratch("can");
    let file = kitchen_with_can_at(&d, "0.4");
    let f = file.to_str().unwrap();
    let can = export(&["export", f, "--object", "can", "--format", "mjcf", "--out", "-"]);
    let reference = export(&["export", f, "--format", "mjcf", "--out", "-"]);
    let (r, l, rho, h, tau) = (0.030, 0.115, 1050.0, 0.040, 0.4);
    let m = rho * PI * r * r * l;
    let object_inertial = |xml: &str| {
        let body = &xml[xml.find("<body name=\"object\"").expect("the object body")..];
        nums(&attr(body, "inertial", "mass", "mass"))[0]
    };
    close(object_inertial(&can), m, "the can's mass ρ π R² L");
    close(object_inertial(&reference), 1000.0 * PI * 0.04 * 0.04 * 0.2, "the reference bottle's mass");
    assert!((object_inertial(&can) - object_inertial(&reference)).abs() > 0.5, "the can weighs as the bottle");
    let size = nums(&attr(&can, "geom", "name=\"object\"", "size"));
    close(size[0], r, "cylinder radius");
    close(size[1], l / 2.0, "cylinder half length");
    let pos = nums(&attr(&can, "body", "name=\"object\"", "pos"));
    close(pos[1], r, "object centre y = R (against the palm)");
    close(pos[2], l / 2.0 - h, "object centre z = L/2 − h_c (on the ground)");
    close(nums(&attr(&can, "geom", "name=\"ground\"", "pos"))[2], -h, "ground z = −h_c");
    for (name, want) in
        [("gripopt_radius", r), ("gripopt_length", l), ("gripopt_grasp_height", h), ("gripopt_tau", tau)]
    {
        close(nums(&attr(&can, "numeric", name, "data"))[0], want, name);
    }
    let ctrl = nums(&attr(&can, "key", "grasp", "ctrl"));
    close(ctrl[0], tau, "keyframe motor torque, finger 1");
    close(ctrl[1], tau, "keyframe motor torque, finger 2");
    close(nums(&attr(&reference, "key", "grasp", "ctrl"))[0], 0.5, "the reference object's motor torque");
    let spring = |xml: &str| nums(&attr(xml, "numeric", "gripopt_tau_s0", "data"))[0];
    assert!(spring(&can) > 0.0 && spring(&can) == spring(&reference), "the spring was resized for the can's torque");
    assert!(can.contains("robust object can"), "the header names the object");
    assert!(!reference.contains("robust object"), "the reference export names no robust object");

    // the build sheet: the same object (mm, g, N·m)
    let j: serde_json::Value =
        serde_json::from_str(&export(&["export", f, "--object", "can", "--format", "json", "--out", "-"])).unwrap();
    close(j["object"]["R_mm"].as_f64().unwrap(), r * 1e3, "sheet R");
    close(j["object"]["L_c_mm"].as_f64().unwrap(), l * 1e3, "sheet L_c");
    close(j["object"]["h_c_mm"].as_f64().unwrap(), h * 1e3, "sheet h_c");
    close(j["object"]["m_c_g"].as_f64().unwrap(), m * 1e3, "sheet m_c");
    close(j["torques"]["tau_Nm"].as_f64().unwrap(), tau, "sheet τ");
    assert!(j["source"].as_str().unwrap().contains("robust object can"), "{j}");
}

/// Every object of the shipped kitchen.toml, by its name, with its mass from the file's
/// numbers; the reference export (no --object) notes that --object exists and lists them.
#[test]
fn every_kitchen_object_exports_with_its_own_mass() {
    // (name, R, L, ρ) as problems/kitchen.toml writes them
    let objects = [
        ("bottle-full", 0.040, 0.200, 1000.0),
        ("bottle-half", 0.040, 0.200, 500.0),
        ("can", 0.030, 0.115, 1050.0),
        ("small-bottle", 0.0325, 0.190, 790.0),
    ];
    for (name, r, l, rho) in objects {
        let xml = export(&["export", KITCHEN, "--object", name, "--format", "mjcf", "--out", "-"]);
        let body = &xml[xml.find("<body name=\"object\"").unwrap()..];
        close(nums(&attr(body, "inertial", "mass", "mass"))[0], rho * PI * r * r * l, name);
        close(nums(&attr(&xml, "geom", "name=\"object\"", "size"))[0], r, name);
    }
    let o = run_gripopt(&["export", KITCHEN, "--format", "mjcf", "--out", "-"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("reference [object]") && e.contains("--object"), "the note names --object: {e}");
    for (name, ..) in objects {
        assert!(e.contains(name), "the note lists {name}: {e}");
    }
}

/// `--object` with an unknown name or on a problem without [robust]: exit 2, naming the
/// flag, the name and (unknown) every known object; nothing written.
#[test]
fn a_bad_object_is_refused_naming_the_flag_and_the_known_objects() {
    let d = scratch("bad");
    let out = d.join("m.xml");
    let o_str = out.to_str().unwrap();
    let o = run_gripopt(&["export", KITCHEN, "--object", "bottle", "--out", o_str]);
    let t = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(t.contains("--object bottle") && t.contains("kitchen.toml") && !t.contains("panicked"), "{t}");
    for name in ["bottle-full", "bottle-half", "can", "small-bottle"] {
        assert!(t.contains(name), "the error lists {name}: {t}");
    }
    assert!(!out.exists(), "a refused export wrote {}", out.display());
    let o = run_gripopt(&["export", BOTTLE_FILE, "--object", "can", "--out", o_str]);
    let t = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(t.contains("--object can") && t.contains("bottle-1l.toml") && t.contains("not robust"), "{t}");
    assert!(!out.exists(), "a refused export wrote {}", out.display());
}

/// kitchen.toml with its reference `[object]` replaced by the can (all four keys as the
/// can's block writes them): the single-object problem the old workaround exported from.
fn kitchen_with_can_as_reference(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(KITCHEN).unwrap();
    let reference = "radius = 0.040       # R (m)\nlength = 0.200       # L_c (m)\ndensity = 1000.0     # rho_c (kg/m^3)\ngrasp_height = 0.050 # h_c, height of the hand plane above the ground (m)\n";
    assert!(text.contains(reference), "problems/kitchen.toml's [object] changed: update this test");
    let can = "radius = 0.030\nlength = 0.115\ndensity = 1050.0\ngrasp_height = 0.040\n";
    let file = dir.join("kitchen-can-reference.toml");
    std::fs::write(&file, text.replacen(reference, can, 1)).unwrap();
    file
}

/// The MJCF without its `source:` line (the only line naming where the design came from).
fn without_source(xml: &str) -> String {
    xml.lines().filter(|l| !l.contains("source: ")).collect::<Vec<_>>().join("\n")
}

/// kitchen.toml's robust setup, the can's index and the first design drawn (seed `seed`)
/// that passes stages 0–2 on the 1 l bottle (object 0) and not on the can, or
/// (`holds_bottle` false) the other way round.
fn kitchen_design(seed: u64, holds_bottle: bool, what: &str) -> (gripopt::eval::Study, usize, gripopt::params::Design) {
    use gripopt::eval::{EvalOptions, Study};
    use rand::SeedableRng;
    let p = gripopt::params::Problem::load(KITCHEN).unwrap();
    let setup = Study::of(&p, &EvalOptions::full(&p));
    let can = (0..setup.objects()).position(|o| setup.object_name(o) == Some("can")).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let x = (0..20_000)
        .map(|_| p.bounds.sample(&mut rng))
        .find(|x| {
            let s = setup.start(x);
            let (bottle, on_can) = (matches!(s.objects[0], Some(Ok(_))), matches!(s.objects[can], Some(Ok(_))));
            bottle == holds_bottle && on_can != holds_bottle
        })
        .expect(what);
    (setup, can, x)
}

/// `--object can` is the single-object export of a problem whose `[object]` is the can (the
/// grip torque and the hand's τ both 0.5 N·m): the same file but for its source line, for
/// the nominal design and for a design that holds the bottle but is discarded at stage 2 on
/// the can (its header then says so, as the single-object pipeline does for that problem).
#[test]
fn an_object_export_equals_the_export_of_that_object_as_reference() {
    let d = scratch("as-reference");
    let single = kitchen_with_can_as_reference(&d);
    let single = single.to_str().unwrap();
    let (_, _, split) = kitchen_design(3, true, "a design holding the bottle but not the can");
    let a = split.to_array();
    let names = ["l21", "b", "t22", "r", "p", "psi_deg"];
    let split = names.iter().zip(a).map(|(n, v)| format!("{n}={v}")).collect::<Vec<_>>().join(",");
    for design in [None, Some(split.as_str())] {
        let with = |args: &[&str]| {
            let mut v = args.to_vec();
            if let Some(x) = design {
                v.extend(["--design", x]);
            }
            export(&v)
        };
        let by_object = with(&["export", KITCHEN, "--object", "can", "--format", "mjcf", "--out", "-"]);
        let by_file = with(&["export", single, "--format", "mjcf", "--out", "-"]);
        // the object's verdict names it: "discarded at stage 2 on object can: <the reason>"
        let by_object =
            without_source(&by_object).replace("discarded at stage 2 on object can:", "discarded at stage 2:");
        let by_file = without_source(&by_file);
        let differ = by_object.lines().zip(by_file.lines()).find(|(a, b)| a != b);
        assert!(differ.is_none() && by_object.len() == by_file.len(), "design {design:?}: {differ:?}");
        let header = by_object.lines().find(|l| l.contains("stages 0-2:")).unwrap().to_string();
        match design {
            None => assert!(header.contains("stages 0-2: passes"), "{header}"),
            Some(_) => assert!(header.contains("discarded at stage 2: "), "{header}"),
        }
    }
}

/// A design of a robust run folder (kitchen.toml, a tiny run) exports on one of the run's
/// objects by id, the source naming the run, the design and the object; a wrong name is
/// refused listing the run's objects.
#[test]
fn a_robust_runs_design_exports_on_an_object() {
    let d = scratch("run");
    let dir = d.join("kitchen-run");
    let r = dir.to_str().unwrap();
    let args = ["optimise", KITCHEN, "--out", r, "--pop", "4", "--generations", "1", "--seed", "1", "--threads", "1"];
    let o = run_gripopt(&args);
    assert!(o.status.success(), "{}", output_text(&o));
    let o = run_gripopt(&["export", r, "--design", "1", "--object", "can", "--format", "mjcf", "--out", "-"]);
    assert!(o.status.success(), "{}", output_text(&o));
    let xml = String::from_utf8(o.stdout).unwrap();
    let body = &xml[xml.find("<body name=\"object\"").unwrap()..];
    close(nums(&attr(body, "inertial", "mass", "mass"))[0], 1050.0 * PI * 0.03 * 0.03 * 0.115, "the can's mass");
    let source = xml.lines().find(|l| l.contains("source: ")).unwrap();
    assert!(source.contains(r) && source.contains("design 1") && source.contains("robust object can"), "{source}");
    let o = run_gripopt(&["export", r, "--design", "1", "--object", "tin", "--format", "mjcf", "--out", "-"]);
    let t = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(t.contains("--object tin") && t.contains("bottle-full, bottle-half, can, small-bottle"), "{t}");
}

/// A design that holds the can but not the 1 l bottle: its export on the can says it passes
/// stages 0–2 there and that the robust design is discarded (on the bottle), as the robust
/// evaluation's own stage-2 result says; on the bottle it is discarded.
#[test]
fn an_object_export_says_when_the_robust_design_fails_on_another_object() {
    use gripopt::export::{ExportScene, ExportedDesign};
    let (setup, can, x) = kitchen_design(4, false, "a design holding the can but not the bottle");
    let free = ExportScene::free(0.0);
    let on_can = ExportedDesign::on_object(&x, &setup, can, free, "t").unwrap().statics_discard.unwrap();
    assert!(
        on_can.starts_with(
            "passes stages 0-2 on object can; the robust design is discarded at stage 2 (object bottle-full:"
        ),
        "{on_can}"
    );
    let on_bottle = ExportedDesign::on_object(&x, &setup, 0, free, "t").unwrap().statics_discard.unwrap();
    assert!(on_bottle.starts_with("discarded at stage 2 on object bottle-full:"), "{on_bottle}");
    let e = ExportedDesign::on_object(&x, &setup, 9, free, "t").unwrap_err();
    assert!(e.is_input(), "{e}");
}

/// `--object ''` read `--object : kitchen.toml: no such robust object`: a name that reads as
/// nothing (empty, blanks) is quoted; a plain one is not.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn an_object_name_that_reads_as_nothing_is_quoted() {
    let kitchen = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");
    for (name, shown) in [("", "--object \"\":"), ("can ", "--object \"can \":"), ("mug", "--object mug:")] {
        let o = run_gripopt(&["simulate", kitchen, "--object", name]);
        let e = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(e.contains(shown) && e.contains("no such robust object"), "{name:?}: {e}");
    }
}
