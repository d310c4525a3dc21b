//! `check`'s recommendation and `fix`, end to end, on files that fail for each cause: the
//! motor's speed (samples/over-limit.gcode), accelerations and corners (tests/fixtures/tune
//! on a weak test machine). What is reported is verified independently: the limits are
//! written into a profile and the file's own limit commands, and `check` must pass.

mod common;
use common::{repo, run, stderr, stdout};

use std::path::Path;

const WEAK: &str = "tests/fixtures/profiles/kossel-weak.yaml";
const KOSSEL: &str = "machines/kossel.yaml";

/// (file, profile, the limit that must come down: 0 accel, 1 scv, 2 velocity)
const CASES: [(&str, &str, usize); 3] = [
    ("samples/over-limit.gcode", KOSSEL, 2),
    ("tests/fixtures/tune/accel.gcode", WEAK, 0),
    ("tests/fixtures/tune/corner.gcode", WEAK, 1),
];

fn p(path: &str) -> String {
    repo(path).display().to_string()
}

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(out)))
}

/// The limits [accel, scv, velocity] the file itself uses at most (its commands and the
/// profile's), read here from the text.
fn file_peak(gcode: &str, profile: &str) -> [f64; 3] {
    let mut peak = [0.0_f64; 3];
    for (i, key) in [
        "max_accel_mm_s2:",
        "square_corner_velocity_mm_s:",
        "max_velocity_mm_s:",
    ]
    .iter()
    .enumerate()
    {
        let line = profile
            .lines()
            .find(|l| l.trim_start().starts_with(key))
            .unwrap();
        let v = line.split(':').nth(1).unwrap().split('#').next().unwrap();
        peak[i] = v.trim().parse().unwrap();
    }
    for line in gcode.lines() {
        for (i, key) in ["ACCEL=", "SQUARE_CORNER_VELOCITY=", "VELOCITY="]
            .iter()
            .enumerate()
        {
            for w in line.split_whitespace() {
                if let Some(v) = w.strip_prefix(key) {
                    peak[i] = peak[i].max(v.parse().unwrap());
                }
            }
        }
        if let Some(rest) = line.strip_prefix("M204 S") {
            peak[0] = peak[0].max(rest.trim().parse().unwrap());
        }
    }
    peak
}

/// The file with every limit capped at `caps` [accel, scv, velocity], the way a user
/// applies a recommendation: the file's own commands capped, and the profile's limits
/// (`in_profile`) or a command at the start of the file; written into `dir`.
fn apply_caps(
    gcode: &str,
    profile: &str,
    caps: [f64; 3],
    in_profile: bool,
    dir: &Path,
) -> (String, String) {
    let keys = ["ACCEL=", "SQUARE_CORNER_VELOCITY=", "VELOCITY="];
    let own = file_peak("", profile);
    let start = [0, 1, 2].map(|i| caps[i].min(own[i]));
    let mut text = if in_profile {
        String::new()
    } else {
        format!(
            "SET_VELOCITY_LIMIT ACCEL={} SQUARE_CORNER_VELOCITY={} VELOCITY={}\n",
            start[0], start[1], start[2]
        )
    };
    for line in gcode.lines() {
        let mut out: Vec<String> = Vec::new();
        for w in line.split(' ') {
            let capped = keys.iter().enumerate().find_map(|(i, k)| {
                let v: f64 = w.strip_prefix(k)?.parse().ok()?;
                Some(format!("{k}{}", v.min(caps[i])))
            });
            out.push(capped.unwrap_or_else(|| w.to_string()));
        }
        let mut l = out.join(" ");
        if let Some(rest) = l.strip_prefix("M204 S") {
            let v: f64 = rest.trim().parse().unwrap();
            l = format!("M204 S{}", v.min(caps[0]));
        }
        text += &l;
        text.push('\n');
    }
    let mut yaml = String::new();
    for line in profile.lines() {
        let t = line.trim_start();
        let l = if !in_profile {
            line.to_string()
        } else if t.starts_with("max_accel_mm_s2:") {
            format!("  max_accel_mm_s2: {}", start[0])
        } else if t.starts_with("square_corner_velocity_mm_s:") {
            format!("  square_corner_velocity_mm_s: {}", start[1])
        } else if t.starts_with("max_velocity_mm_s:") {
            format!("  max_velocity_mm_s: {}", start[2])
        } else {
            line.to_string()
        };
        yaml += &l;
        yaml.push('\n');
    }
    let g = dir.join("capped.gcode");
    let m = dir.join("capped.yaml");
    std::fs::write(&g, text).unwrap();
    std::fs::write(&m, yaml).unwrap();
    (g.display().to_string(), m.display().to_string())
}

#[test]
fn the_recommendation_passes_and_lowers_the_limit_of_the_cause() {
    for (file, machine, cause) in CASES {
        let o = run(&["check", &p(file), "-m", &p(machine), "--format", "json"]);
        assert_eq!(o.status.code(), Some(1), "{file}: {}", stderr(&o));
        let v = json(&o);
        let r = &v["recommendation"];
        let rec = [
            r["max_accel_mm_s2"].as_f64().unwrap(),
            r["square_corner_velocity_mm_s"].as_f64().unwrap(),
            r["max_velocity_mm_s"].as_f64().unwrap(),
        ];
        let gcode = std::fs::read_to_string(repo(file)).unwrap();
        let profile = std::fs::read_to_string(repo(machine)).unwrap();
        let peak = file_peak(&gcode, &profile);
        // The limit of the cause came down; the others are at most where the file had
        // them (a quicker combination may lower one of them instead of more of the cause).
        for i in 0..3 {
            if i == cause {
                assert!(rec[i] < peak[i], "{file}: {i}: {rec:?} vs {peak:?}");
            } else {
                assert!(rec[i] <= peak[i], "{file}: {i}: {rec:?} vs {peak:?}");
            }
        }
        // Slower than the file as it is, as the report says.
        let t = r["print_time_s"].as_f64().unwrap();
        assert!(
            t >= v["summary"]["print_time_s"].as_f64().unwrap(),
            "{file}"
        );
        // Applied as a user would: the file's commands capped, and a command at its start
        // (the print time is the one reported) or the profile's limits lowered (Klipper's
        // delta edge limits then come down too).
        for in_profile in [false, true] {
            let dir = tempfile::tempdir().unwrap();
            let (g, m) = apply_caps(&gcode, &profile, rec, in_profile, dir.path());
            let c = run(&["check", &g, "-m", &m, "--format", "json"]);
            assert_eq!(c.status.code(), Some(0), "{file}: {rec:?}: {}", stdout(&c));
            let t_capped = json(&c)["summary"]["print_time_s"].as_f64().unwrap();
            if !in_profile {
                assert!((t_capped - t).abs() < 1e-6, "{file}: {t_capped} vs {t}");
            }
        }
        // The text names the limits.
        let text = stdout(&run(&["check", &p(file), "-m", &p(machine)]));
        let want = format!(
            "passes with   ACCEL={} SQUARE_CORNER_VELOCITY={} VELOCITY={}",
            rec[0], rec[1], rec[2]
        );
        assert!(text.contains(&want), "{file}: {text}");
    }
}

#[test]
fn fix_passes_keeps_every_byte_and_is_idempotent() {
    for (file, machine, _) in CASES {
        // Passes, keeps every byte, strips back, idempotent (common::fix).
        let common::fix::Fixed {
            input,
            fixed,
            out,
            dir,
            ..
        } = common::fix::fix_and_verify(file, machine);
        let text = String::from_utf8(fixed).unwrap();
        let added: Vec<&str> = text
            .lines()
            .filter(|l| l.contains("; delta-gcode"))
            .collect();
        assert!(
            added.iter().any(|l| l.starts_with("SET_VELOCITY_LIMIT ")),
            "{file}"
        );
        // Fixing its annotated version changes nothing beyond dropping the notes.
        let annotated = dir.path().join("annotated.gcode");
        let a = run(&[
            "annotate",
            &out.display().to_string(),
            "-m",
            &p(machine),
            "-o",
            &annotated.display().to_string(),
        ]);
        assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
        // `annotate` keeps the commands: the annotated fixed file passes too.
        let ca = run(&["check", &annotated.display().to_string(), "-m", &p(machine)]);
        assert_eq!(ca.status.code(), Some(0), "{}", stdout(&ca));
        run(&["strip", "--in-place", &annotated.display().to_string()]);
        assert_eq!(std::fs::read(&annotated).unwrap(), input, "{file}");
    }
}

#[test]
fn fix_in_place_keeps_crlf_and_the_mode() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("corner.gcode");
    let lf = std::fs::read_to_string(repo("tests/fixtures/tune/corner.gcode")).unwrap();
    let crlf = lf.replace('\n', "\r\n");
    std::fs::write(&f, &crlf).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o640)).unwrap();
    }
    let o = run(&[
        "fix",
        "--in-place",
        &f.display().to_string(),
        "-m",
        &p(WEAK),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = std::fs::read_to_string(&f).unwrap();
    assert!(text.len() > crlf.len());
    for l in text.split_inclusive('\n') {
        assert!(l.ends_with("\r\n"), "{l:?}");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&f).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
    }
    let s = run(&["strip", "--in-place", &f.display().to_string()]);
    assert_eq!(s.status.code(), Some(0));
    assert_eq!(std::fs::read_to_string(&f).unwrap(), crlf);
}

#[test]
fn a_move_no_limit_helps_is_a_clear_error_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("far.gcode");
    let input =
        "G28\nG1 Z10 F6000\nSET_VELOCITY_LIMIT ACCEL=30000\nG1 X40 Y0\nG1 X-40 Y0\nG1 X0 Y-150\n";
    std::fs::write(&f, input).unwrap();
    let out = dir.path().join("out.gcode");
    let o = run(&[
        "fix",
        &f.display().to_string(),
        "-m",
        &p(WEAK),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("line 6 cannot be made to pass"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    assert_eq!(std::fs::read_to_string(&f).unwrap(), input);
    // `check` says why there is no recommendation.
    let c = run(&[
        "check",
        &f.display().to_string(),
        "-m",
        &p(WEAK),
        "--format",
        "json",
    ]);
    assert_eq!(c.status.code(), Some(1));
    let v = json(&c);
    assert!(v.get("recommendation").is_none());
    let why = v["recommendation_error"].as_str().unwrap();
    assert!(why.contains("line 6"), "{why}");
}

#[test]
fn a_passing_file_is_left_as_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.gcode");
    let file = "samples/calib-cube_cura413_kossel-mini.gcode";
    let o = run(&[
        "fix",
        &p(file),
        "-m",
        &p(KOSSEL),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let input = std::fs::read(repo(file)).unwrap();
    let fixed = std::fs::read(&out).unwrap();
    assert_eq!(common::strip_ours(&fixed), input);
    assert!(
        stdout(&o).contains("0 limit commands added"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn machine_maps_the_largest_acceleration_over_the_disc() {
    let o = run(&["machine", &p(WEAK), "--format", "json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let map = &json(&o)["max_accel_map"];
    let at = |key: &str| -> Vec<f64> {
        map[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (rest, moving) = (at("at_rest_mm_s2"), at("at_speed_mm_s2"));
    assert_eq!(rest.len(), 5);
    // The edge of the disc is weaker than the centre; the weak test machine cannot take the
    // 30000 mm/s² of tests/fixtures/tune/accel.gcode anywhere, and takes its 3000 at the
    // centre.
    assert!(rest[4] < rest[0], "{rest:?}");
    assert!(
        rest.iter()
            .chain(&moving)
            .all(|&a| a > 3000.0 && a < 30000.0),
        "{rest:?} {moving:?}"
    );
    let text = stdout(&run(&["machine", &p(WEAK)]));
    assert!(
        text.contains("largest acceleration in the worst direction at the bed"),
        "{text}"
    );
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display().to_string();
    let o = run(&["machine", &p(WEAK), "--plot", &d]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for name in ["kossel-weak-accel-rest.svg", "kossel-weak-accel-speed.svg"] {
        let svg = std::fs::read_to_string(dir.path().join(name)).unwrap();
        assert!(svg.contains("<svg") && svg.contains("max_accel"), "{name}");
    }
}
