//! `fix` run and verified end to end, for any profile: the fixed file passes `check` in the
//! time `fix` reported (no longer than with the limits for the whole file), its lines
//! without ours are the input byte for byte, `strip` gives the input back and fixing it
//! again changes nothing.

use super::{repo, run, stderr, stdout};

/// What a verified fix gave.
pub struct Fixed {
    /// `fix`'s JSON.
    pub json: serde_json::Value,
    pub input: Vec<u8>,
    pub fixed: Vec<u8>,
    /// The fixed file, in `dir`.
    pub out: std::path::PathBuf,
    pub dir: tempfile::TempDir,
}

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(out)))
}

/// Fixes `file` (a path from the repository's top) for the profile `machine`, and checks
/// what the module documentation says.
pub fn fix_and_verify(file: &str, machine: &str) -> Fixed {
    let machine = repo(machine).display().to_string();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fixed.gcode");
    let o = run(&[
        "fix",
        &repo(file).display().to_string(),
        "-m",
        &machine,
        "-o",
        &out.display().to_string(),
        "--format",
        "json",
    ]);
    assert_eq!(o.status.code(), Some(0), "{file}: {}", stderr(&o));
    let f = json(&o);
    let input = std::fs::read(repo(file)).unwrap();
    let fixed = std::fs::read(&out).unwrap();
    assert!(f["commands"].as_u64().unwrap() > 0, "{file}");
    let c = run(&[
        "check",
        &out.display().to_string(),
        "-m",
        &machine,
        "--format",
        "json",
    ]);
    assert_eq!(c.status.code(), Some(0), "{file}: {}", stdout(&c));
    let t = json(&c)["summary"]["print_time_s"].as_f64().unwrap();
    assert!(
        (t - f["print_time_s"].as_f64().unwrap()).abs() < 1e-9,
        "{file}"
    );
    let t_rec = f["recommendation"]["print_time_s"].as_f64().unwrap();
    assert!(
        t <= t_rec + 1e-9,
        "{file}: fix {t} s, recommendation {t_rec} s"
    );
    let kept: Vec<u8> = fixed
        .split_inclusive(|b| *b == b'\n')
        .filter(|l| !String::from_utf8_lossy(l).contains("; delta-gcode"))
        .flatten()
        .copied()
        .collect();
    assert_eq!(kept, input, "{file}");
    let stripped = dir.path().join("stripped.gcode");
    let s = run(&[
        "strip",
        &out.display().to_string(),
        "-o",
        &stripped.display().to_string(),
    ]);
    assert_eq!(s.status.code(), Some(0), "{}", stderr(&s));
    assert_eq!(std::fs::read(&stripped).unwrap(), input, "{file}");
    let again = dir.path().join("again.gcode");
    let o2 = run(&[
        "fix",
        &out.display().to_string(),
        "-m",
        &machine,
        "-o",
        &again.display().to_string(),
    ]);
    assert_eq!(o2.status.code(), Some(0), "{}", stderr(&o2));
    assert_eq!(std::fs::read(&again).unwrap(), fixed, "{file}");
    Fixed {
        json: f,
        input,
        fixed,
        out,
        dir,
    }
}
