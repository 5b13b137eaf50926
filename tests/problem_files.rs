//! Problem-file validation: every malformed file gives an error naming the file and field.
use gripopt::params::{Design, Problem};
use std::path::Path;

fn base() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap()
}

fn err_of(text: &str) -> String {
    Problem::from_toml_str(text, Path::new("bad.toml")).unwrap_err().to_string()
}

#[test]
fn all_shipped_problems_load() {
    for name in ["bottle-1l", "can", "light-bottle"] {
        let p = Problem::load(format!("{}/problems/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
        assert_eq!(p.name, name);
    }
    let p = crate::common::bottle();
    assert_eq!(p.nominal, Design::nominal());
    assert!((p.scene.object.radius - 0.040).abs() < 1e-15);
}

/// Each malformed edit of the default file is refused with an error naming the file, the
/// field and what is wrong.
#[test]
fn malformed_values_name_the_file_and_field() {
    for (from, to, expected) in [
        ("tau = 0.5 ", "tau = nan ", &["hand.tau", "finite"][..]),
        ("radius = 0.040 ", "radius = -0.040 ", &["object.radius", "> 0"]),
        ("t22 = [0.015, 0.060]", "t22 = [0.060, 0.015]", &["bounds.t22", "lower bound"]),
        ("mu_s = 0.6 ", "mu_s = 0.6\nmu_x = 0.1 ", &["mu_x"]),
        ("v_min = 1e-3 ", "# v_min removed ", &["v_min"]),
        ("restitution = 0.3 ", "restitution = 1.5 ", &["contact.restitution"]),
        ("v_d = 10e-3 ", "v_d = 1e-3 ", &["contact.v_d"]),
    ] {
        let text = base();
        assert!(text.contains(from), "bottle-1l.toml lacks {from:?}");
        let e = err_of(&text.replace(from, to));
        assert!(e.contains("bad.toml") && expected.iter().all(|x| e.contains(x)), "{to:?}: {e}");
    }
}

#[test]
fn unreadable_file_names_the_path() {
    let e = Problem::load("/nonexistent/dir/p.toml").unwrap_err().to_string();
    assert!(e.contains("/nonexistent/dir/p.toml"), "{e}");
}

#[test]
fn design_assignments() {
    let d = Design::parse_assignments("l21=0.0494,b=0.056,t22=0.0376,r=0.46,p=0.4,psi_deg=129.76").unwrap();
    assert!((d.psi.to_degrees() - 129.76).abs() < 1e-12);
    assert!(Design::parse_assignments("l21=0.05").unwrap_err().to_string().contains("missing"));
    assert!(Design::parse_assignments("l21=0.05,l21=0.04").unwrap_err().to_string().contains("twice"));
    assert!(Design::parse_assignments("x=1").unwrap_err().to_string().contains("unknown"));
    assert!(Design::parse_assignments("l21=abc").unwrap_err().to_string().contains("not a number"));
    assert!(Design::parse_assignments("l21=nan,b=1,t22=1,r=1,p=1,psi_deg=1")
        .unwrap_err()
        .to_string()
        .contains("finite"));
}

/// Sets `section.key` of the default file to `value` (a TOML value) and returns the error text.
fn err_with(section: &str, key: &str, value: toml::Value) -> String {
    let mut t: toml::Table = base().parse().unwrap();
    t.get_mut(section).and_then(|s| s.as_table_mut()).unwrap().insert(key.into(), value);
    err_of(&toml::to_string(&t).unwrap())
}

/// Every numeric field of the file refuses an absurd value with an error naming it
/// (before the limits, 1e300 was accepted in 34 fields, and `g = 1e300` made the nominal
/// design feasible).
#[test]
fn absurd_values_are_refused_in_every_field() {
    let mut checked = 0;
    for l in gripopt::params::LIMITS {
        let Some((section, key)) = l.field.split_once('.') else { continue };
        let big = if key == "max_steps" { toml::Value::Integer(i64::MAX) } else { toml::Value::Float(1e300) };
        let value = if key == "r_sing" { toml::Value::Array(vec![toml::Value::Float(1e300)]) } else { big };
        let e = err_with(section, key, value);
        assert!(e.contains("bad.toml") && e.contains(l.field), "{}: {e}", l.field);
        checked += 1;
    }
    assert!(checked >= 38, "{checked}");
    for name in ["l21", "b", "t22", "r", "p", "psi_deg"] {
        let e = err_with("nominal", name, toml::Value::Float(1e300));
        assert!(e.contains(&format!("nominal.{name}")), "{e}");
        let e = err_with("bounds", name, toml::Value::Array(vec![toml::Value::Float(0.01), toml::Value::Float(1e300)]));
        assert!(e.contains(&format!("bounds.{name}")), "{e}");
    }
}

#[test]
fn bounds_need_exactly_two_numbers_and_sweep_step_a_floor() {
    let three = toml::Value::Array(vec![0.03.into(), 0.05.into(), 0.07.into()]);
    let e = err_with("bounds", "l21", three);
    assert!(e.contains("bounds.l21") && e.contains("exactly two"), "{e}");
    let e = err_with("criteria", "sweep_step_deg", toml::Value::Float(1e-300));
    assert!(e.contains("criteria.sweep_step_deg") && e.contains(">= 0.01"), "{e}");
    let e = err_with("criteria", "r_sing", toml::Value::Array(vec![0.04.into(); 101]));
    assert!(e.contains("criteria.r_sing") && e.contains("at most 100"), "{e}");
}

/// A problem file is read only when it is a regular file, with a size cap: `/dev/zero` is
/// refused before it is opened (hostile pass 34), a file over 1 MiB before it is parsed.
#[test]
fn endless_or_huge_files_are_refused() {
    if std::path::Path::new("/dev/zero").exists() {
        let e = Problem::load("/dev/zero").unwrap_err().to_string();
        assert!(e.contains("/dev/zero") && e.contains("not a regular file (a device"), "{e}");
    }
    let d = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/problem-files-huge"));
    std::fs::create_dir_all(&d).unwrap();
    let huge = d.join("huge.toml");
    std::fs::File::create(&huge).unwrap().set_len(gripopt::params::MAX_FILE_BYTES + 1).unwrap();
    let e = Problem::load(&huge).unwrap_err().to_string();
    assert!(e.contains("huge.toml") && e.contains("bytes"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// docs/problem-files.md lists every limit exactly as the code checks it.
#[test]
fn the_documented_limits_are_the_checked_ones() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/problem-files.md")).unwrap();
    for l in gripopt::params::LIMITS {
        let name =
            if l.field.contains('.') { l.field.to_string() } else { format!("nominal.{0}, bounds.{0}", l.field) };
        let row = format!("| `{name}` | {} | {} |", l.range(), l.unit);
        assert!(doc.contains(&row), "docs/problem-files.md lacks the row {row}");
    }
}

/// A count may be written as a whole float (`1e8`, the way docs/problem-files.md writes the
/// limit), in every count field alike; a fraction is refused naming the field.
#[test]
fn counts_are_whole_numbers_however_written() {
    let with = |section: &str, key: &str, value: toml::Value| {
        let mut t: toml::Table = base().parse().unwrap();
        t.get_mut(section).and_then(|s| s.as_table_mut()).unwrap().insert(key.into(), value);
        Problem::from_toml_str(&toml::to_string(&t).unwrap(), Path::new("bad.toml"))
    };
    let p = with("solver", "max_steps", toml::Value::Float(1e8)).unwrap();
    assert_eq!(p.solver.max_steps, 100_000_000);
    let p = with("scene", "ground_points", toml::Value::Float(16.0)).unwrap();
    assert_eq!(p.scene.setup.ground_points, 16);
    for (section, key) in [("solver", "max_steps"), ("scene", "ground_points")] {
        let e = with(section, key, toml::Value::Float(5.5)).unwrap_err().to_string();
        assert!(e.contains("bad.toml") && e.contains(&format!("{section}.{key}")) && e.contains("whole"), "{e}");
    }
}

/// Issue 44 class 8: `criteria.eta_stab` below ~1e-11 let the stability event fire on the
/// rounding noise of the excess energy (t_stab stopped growing as the threshold fell): the
/// field's lower limit is 1e-10, and the error says why.
#[test]
fn eta_stab_below_its_noise_floor_is_refused_with_the_reason() {
    let edit = |v: &str| base().replace("eta_stab = 2.5e-3", &format!("eta_stab = {v}"));
    let e = err_of(&edit("1e-11"));
    assert!(e.contains("criteria.eta_stab") && e.contains("1e-10") && e.contains("rounding noise"), "{e}");
    assert!(Problem::from_toml_str(&edit("1e-10"), Path::new("ok.toml")).is_ok());
}

/// Issue 44 class 8: a problem file with a 400 000-level nested array echoed the whole
/// 800 kB line in its error; what a message echoes of a file is cut to a readable length.
#[test]
fn a_huge_line_is_not_echoed_whole() {
    let text =
        base().replacen("name = ", &format!("deep = {}{}\nname = ", "[".repeat(400_000), "]".repeat(400_000)), 1);
    let e = err_of(&text);
    assert!(e.len() < 4000, "{} bytes of error", e.len());
    assert!(e.contains("bad.toml") && e.contains("more characters"), "{}", &e[..e.len().min(600)]);
    let d = crate::common::scratch_dir("problem-files", "i44-deep");
    std::fs::write(d.join("deep.toml"), &text).unwrap();
    let o = crate::common::run_gripopt(&["evaluate", d.join("deep.toml").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stderr.len() < 4000, "{} bytes on stderr", o.stderr.len());
}
