//! `check`'s recommendation and `fix` for a Marlin profile, end to end, on files that fail
//! for each cause (tests/fixtures/tune/marlin): accelerations (M204), corners (the towers'
//! classic jerk, M205) and the motor's speed (the towers' feedrate, M203). What is reported
//! is verified from the text alone: the settings, read here from the G-code lines as
//! Marlin reads them, are written into the file, and `check` must pass.

mod common;
use common::{repo, run, stderr, stdout};

const WEAK: &str = "tests/fixtures/profiles/marlin-q5-weak.yaml";
const CURVE: &str = "tests/fixtures/profiles/kossel-marlin-curve.yaml";

/// (file, profile, the setting that must come down: 0 M204, 1 M205, 2 M203)
const CASES: [(&str, &str, usize); 3] = [
    ("tests/fixtures/tune/marlin/accel.gcode", WEAK, 0),
    ("tests/fixtures/tune/marlin/corner.gcode", WEAK, 1),
    ("tests/fixtures/tune/marlin/speed.gcode", CURVE, 2),
];

fn p(path: &str) -> String {
    repo(path).display().to_string()
}

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(out)))
}

/// Marlin's settings the tuning changes: M204 P, T; M205 X, Y, Z; M203 X, Y, Z.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Settings([f64; 8]);

impl Settings {
    /// The profile's `marlin:` figures.
    fn of_profile(yaml: &str) -> Settings {
        let value = |key: &str| -> Vec<f64> {
            let line = yaml
                .lines()
                .find(|l| l.trim_start().starts_with(key))
                .unwrap_or_else(|| panic!("{key}"));
            let v = line.split(':').nth(1).unwrap().split('#').next().unwrap();
            v.trim()
                .trim_matches(|c| c == '[' || c == ']')
                .split(',')
                .map(|x| x.trim().parse().unwrap())
                .collect()
        };
        let (p, t) = (
            value("print_accel_mm_s2:")[0],
            value("travel_accel_mm_s2:")[0],
        );
        let (j, f) = (value("jerk_mm_s:"), value("max_feedrate_mm_s:"));
        Settings([p, t, j[0], j[1], j[2], f[0], f[1], f[2]])
    }

    /// After one G-code line, as Marlin reads M204 (S sets P and T), M205 and M203.
    fn apply(&mut self, line: &str) {
        let code = line.split(';').next().unwrap_or("");
        let mut words = code.split_whitespace();
        let slots: &[(char, usize)] = match words.next() {
            Some("M204") => &[('S', 0), ('S', 1), ('P', 0), ('T', 1)],
            Some("M205") => &[('X', 2), ('Y', 3), ('Z', 4)],
            Some("M203") => &[('X', 5), ('Y', 6), ('Z', 7)],
            _ => return,
        };
        let words: Vec<&str> = words.collect();
        for &(letter, i) in slots {
            if let Some(v) = words.iter().find_map(|w| w.strip_prefix(letter)) {
                self.0[i] = v.parse().unwrap();
            }
        }
    }

    /// The largest of each cause: [M204, M205, M203].
    fn causes(&self) -> [f64; 3] {
        let s = self.0;
        [
            s[0].max(s[1]),
            s[2].max(s[3]).max(s[4]),
            s[5].max(s[6]).max(s[7]),
        ]
    }
}

/// The settings in force at each G0/G1 of `gcode`, and at its end.
fn settings_at_moves(gcode: &str, profile: &str) -> (Vec<Settings>, Settings) {
    let mut s = Settings::of_profile(profile);
    let mut at = Vec::new();
    for line in gcode.lines() {
        s.apply(line);
        if line.starts_with("G0 ") || line.starts_with("G1 ") {
            at.push(s);
        }
    }
    (at, s)
}

/// The file as a user applies a recommendation: Marlin's settings lowered to it where they
/// are higher (commands at the start), and the file's own M204 / M205 / M203 capped at it.
fn apply_recommendation(gcode: &str, own: &Settings, rec: &[f64; 4], caps: [f64; 3]) -> String {
    let s = own.0;
    let m = |i: usize, r: f64| s[i].min(r);
    let mut text = format!(
        "M204 P{} T{}\nM205 X{} Y{} Z{}\nM203 X{} Y{} Z{}\n",
        m(0, rec[0]),
        m(1, rec[1]),
        m(2, rec[2]),
        m(3, rec[2]),
        m(4, rec[2]),
        m(5, rec[3]),
        m(6, rec[3]),
        m(7, rec[3])
    );
    for line in gcode.lines() {
        let cap = match line.split_whitespace().next() {
            Some("M204") => Some(caps[0]),
            Some("M205") => Some(caps[1]),
            Some("M203") => Some(caps[2]),
            _ => None,
        };
        let l = match cap {
            Some(c) if !line.starts_with(';') => line
                .split(' ')
                .map(|w| match w.get(1..).and_then(|v| v.parse::<f64>().ok()) {
                    Some(v) if w.starts_with(['S', 'P', 'T', 'X', 'Y', 'Z']) => {
                        format!("{}{}", &w[..1], v.min(c))
                    }
                    _ => w.to_string(),
                })
                .collect::<Vec<_>>()
                .join(" "),
            _ => line.to_string(),
        };
        text += &l;
        text.push('\n');
    }
    text
}

#[test]
fn the_recommendation_names_marlin_s_commands_and_passes() {
    for (file, machine, cause) in CASES {
        let o = run(&["check", &p(file), "-m", &p(machine), "--format", "json"]);
        assert_eq!(o.status.code(), Some(1), "{file}: {}", stderr(&o));
        let v = json(&o);
        let r = &v["recommendation"];
        let m = &r["marlin"];
        let rec = [
            r["max_accel_mm_s2"].as_f64().unwrap(),
            r["square_corner_velocity_mm_s"].as_f64().unwrap(),
            r["max_velocity_mm_s"].as_f64().unwrap(),
        ];
        assert_eq!(m["jerk_mm_s"].as_f64(), Some(rec[1]), "{file}");
        assert_eq!(m["max_feedrate_mm_s"].as_f64(), Some(rec[2]), "{file}");
        let (print, travel) = (
            m["print_accel_mm_s2"].as_f64().unwrap(),
            m["travel_accel_mm_s2"].as_f64().unwrap(),
        );
        assert_eq!(print.max(travel), rec[0], "{file}");
        let commands: Vec<String> = m["commands"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap().to_string())
            .collect();
        assert_eq!(
            commands,
            [
                format!("M204 P{print} T{travel}"),
                format!("M205 X{0} Y{0} Z{0}", rec[1]),
                format!("M203 X{0} Y{0} Z{0}", rec[2]),
            ],
            "{file}"
        );
        // The setting of the cause came down below the most the file used.
        let gcode = std::fs::read_to_string(repo(file)).unwrap();
        let profile = std::fs::read_to_string(repo(machine)).unwrap();
        let (at, _) = settings_at_moves(&gcode, &profile);
        let peak = at.iter().fold([0.0_f64; 3], |acc, s| {
            let c = s.causes();
            [0, 1, 2].map(|i| acc[i].max(c[i]))
        });
        assert!(rec[cause] < peak[cause], "{file}: {rec:?} vs {peak:?}");
        for i in 0..3 {
            assert!(rec[i] <= peak[i], "{file}: {rec:?} vs {peak:?}");
        }
        let t = r["print_time_s"].as_f64().unwrap();
        assert!(
            t >= v["summary"]["print_time_s"].as_f64().unwrap(),
            "{file}"
        );
        // Applied as a user would, from the commands' text: it passes, in the time reported.
        let dir = tempfile::tempdir().unwrap();
        let g = dir.path().join("capped.gcode");
        let own = Settings::of_profile(&profile);
        let marlin = [print, travel, rec[1], rec[2]];
        std::fs::write(&g, apply_recommendation(&gcode, &own, &marlin, rec)).unwrap();
        let c = run(&[
            "check",
            &g.display().to_string(),
            "-m",
            &p(machine),
            "--format",
            "json",
        ]);
        assert_eq!(c.status.code(), Some(0), "{file}: {rec:?}: {}", stdout(&c));
        let t_capped = json(&c)["summary"]["print_time_s"].as_f64().unwrap();
        assert!((t_capped - t).abs() < 1e-6, "{file}: {t_capped} vs {t}");
        // The text names the commands.
        let text = stdout(&run(&["check", &p(file), "-m", &p(machine)]));
        let want = format!("passes with   {}: print time", commands.join(", "));
        assert!(text.contains(&want), "{file}: {text}");
    }
}

#[test]
fn fix_inserts_marlin_s_commands_restores_the_file_s_own_and_is_idempotent() {
    for (file, machine, cause) in CASES {
        // Passes in the time reported, keeps every byte, strips back, idempotent.
        let common::fix::Fixed {
            json, input, fixed, ..
        } = common::fix::fix_and_verify(file, machine);
        // Every added line is one of Marlin's commands.
        let text = String::from_utf8(fixed).unwrap();
        let added: Vec<&str> = text
            .lines()
            .filter(|l| l.ends_with("; delta-gcode"))
            .collect();
        assert_eq!(
            added.len() as u64,
            json["commands"].as_u64().unwrap(),
            "{file}"
        );
        for l in &added {
            assert!(
                ["M204 ", "M205 ", "M203 "].iter().any(|c| l.starts_with(c)),
                "{file}: {l}"
            );
        }
        // At every move the settings are the file's or below, the cause's lower at some;
        // at the end the file's own again.
        let profile = std::fs::read_to_string(repo(machine)).unwrap();
        let input = String::from_utf8(input).unwrap();
        let (orig, orig_end) = settings_at_moves(&input, &profile);
        let (capped, capped_end) = settings_at_moves(&text, &profile);
        assert_eq!(orig.len(), capped.len(), "{file}");
        let mut lowered = false;
        for (o, c) in orig.iter().zip(&capped) {
            for i in 0..8 {
                assert!(c.0[i] <= o.0[i], "{file}: {c:?} vs {o:?}");
            }
            lowered |= c.causes()[cause] < o.causes()[cause];
        }
        assert!(lowered, "{file}");
        assert_eq!(capped_end, orig_end, "{file}");
    }
}

#[test]
fn fix_reads_standard_input_and_writes_standard_output() {
    let (file, machine, _) = CASES[1];
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fixed.gcode");
    let o = run(&[
        "fix",
        &p(file),
        "-m",
        &p(machine),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let input = std::fs::read(repo(file)).unwrap();
    let piped = common::bin()
        .args(["fix", "-", "-m", &p(machine), "-o", "-"])
        .stdin(std::fs::File::open(repo(file)).unwrap())
        .output()
        .unwrap();
    assert_eq!(piped.status.code(), Some(0), "{}", stderr(&piped));
    // The same G-code as from the file, and only G-code on stdout; the report on stderr.
    assert_eq!(piped.stdout, std::fs::read(&out).unwrap());
    let kept: Vec<u8> = piped
        .stdout
        .split_inclusive(|b| *b == b'\n')
        .filter(|l| !l.ends_with(b"; delta-gcode\n"))
        .flatten()
        .copied()
        .collect();
    assert_eq!(common::strip_ours(&kept), input);
    assert!(
        stderr(&piped).contains("limit commands added"),
        "{}",
        stderr(&piped)
    );
    assert!(
        stderr(&piped).contains("<stdout>: OK"),
        "{}",
        stderr(&piped)
    );
    // Standard input cannot be replaced in place.
    let o = run(&["fix", "-", "--in-place", "-m", &p(machine)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--in-place needs a file"),
        "{}",
        stderr(&o)
    );
}
