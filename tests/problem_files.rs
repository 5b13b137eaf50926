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

#[test]
fn nan_value() {
    let e = err_of(&base().replace("tau = 0.5 ", "tau = nan "));
    assert!(e.contains("bad.toml") && e.contains("hand.tau") && e.contains("finite"), "{e}");
}

#[test]
fn negative_length() {
    let e = err_of(&base().replace("radius = 0.040 ", "radius = -0.040 "));
    assert!(e.contains("bad.toml") && e.contains("object.radius") && e.contains("> 0"), "{e}");
}

#[test]
fn bounds_reversed() {
    let e = err_of(&base().replace("t22 = [0.015, 0.060]", "t22 = [0.060, 0.015]"));
    assert!(e.contains("bad.toml") && e.contains("bounds.t22") && e.contains("lower bound"), "{e}");
}

#[test]
fn unknown_key() {
    let e = err_of(&base().replace("mu_s = 0.6 ", "mu_s = 0.6\nmu_x = 0.1 "));
    assert!(e.contains("bad.toml") && e.contains("mu_x"), "{e}");
}

#[test]
fn missing_field() {
    let e = err_of(&base().replace("v_min = 1e-3 ", "# v_min removed "));
    assert!(e.contains("bad.toml") && e.contains("v_min"), "{e}");
}

#[test]
fn restitution_out_of_range_and_velocity_order() {
    let e = err_of(&base().replace("restitution = 0.3 ", "restitution = 1.5 "));
    assert!(e.contains("contact.restitution"), "{e}");
    let e = err_of(&base().replace("v_d = 10e-3 ", "v_d = 1e-3 "));
    assert!(e.contains("contact.v_d"), "{e}");
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
    assert!(Design::parse_assignments("l21=nan,b=1,t22=1,r=1,p=1,psi_deg=1").unwrap_err().to_string().contains("finite"));
}
