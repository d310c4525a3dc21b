//! Every shipped machine profile loads, and the shipped calibration cube checks on it.

mod common;

use common::*;

#[test]
fn every_shipped_profile_is_valid_and_checks_the_cube() {
    let cube = repo("samples/calib-cube_cura413_kossel-mini.gcode")
        .display()
        .to_string();
    let mut n = 0;
    for entry in std::fs::read_dir(repo("machines")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        n += 1;
        let p = path.display().to_string();
        let m = run(&["machine", &p]);
        assert_eq!(m.status.code(), Some(0), "{p}: {}", stderr(&m));
        let c = run(&["check", &cube, "-m", &p, "--format", "json"]);
        assert!(
            matches!(c.status.code(), Some(0 | 1)),
            "{p}: {}",
            stderr(&c)
        );
        let v: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
        assert!(v["summary"]["moves"].as_u64().unwrap_or(0) > 8000, "{p}");
    }
    assert!(n >= 6, "{n} profiles");
}
