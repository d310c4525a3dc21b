use super::*;

fn words(p: &ParsedLine) -> Vec<(char, Option<f64>, u32)> {
    p.words()
        .iter()
        .map(|w| (char::from(w.letter), w.value, w.column))
        .collect()
}

fn code(p: &ParsedLine) -> (u8, u32) {
    match p.command {
        Command::Code { letter, number, .. } => (letter, number),
        other => panic!("not a code: {other:?}"),
    }
}

#[test]
fn line_number_and_good_checksum() {
    // Checksum by hand: XOR of the bytes of "N123 G1 X10 Y20".
    let body = b"N123 G1 X10 Y20";
    let cs = body.iter().fold(0u8, |a, b| a ^ b);
    let line = format!("N123 G1 X10 Y20*{cs}\n");
    let p = parse_line(line.as_bytes());
    assert_eq!(p.line_number, Some(123));
    assert_eq!(p.checksum, Some(u32::from(cs)));
    assert_eq!(code(&p), (b'G', 1));
    assert_eq!(words(&p), vec![('X', Some(10.0), 9), ('Y', Some(20.0), 13)]);
    assert!(p.diags().is_empty(), "{:?}", p.diags());
}

#[test]
fn wrong_checksum_is_a_warning_at_the_star() {
    let p = parse_line(b"N123 G1 X10 Y20*43");
    let cs = b"N123 G1 X10 Y20".iter().fold(0u8, |a, b| a ^ b);
    assert_eq!(cs, 42);
    assert_eq!(
        p.diags(),
        &[LineDiag {
            column: 16,
            severity: Severity::Warning,
            kind: DiagKind::Checksum {
                computed: cs,
                written: 43
            }
        }]
    );
    assert_eq!(p.value(b'Y'), Some(20.0));
}

#[test]
fn t_is_a_parameter_of_m204_and_m104() {
    let p = parse_line(b"M204 P1500 T3000");
    assert_eq!(code(&p), (b'M', 204));
    assert_eq!(p.value(b'P'), Some(1500.0));
    assert_eq!(p.value(b'T'), Some(3000.0));
    let p = parse_line(b"M104 S215 T1");
    assert_eq!(code(&p), (b'M', 104));
    assert_eq!(p.value(b'T'), Some(1.0));
}

#[test]
fn tool_change_is_a_command() {
    let p = parse_line(b"T0\n");
    assert_eq!(code(&p), (b'T', 0));
    assert!(p.words().is_empty());
}

#[test]
fn m117_free_text_until_semicolon() {
    let p = parse_line(b"M117 text X1 (y) ; with semicolons; more\r\n");
    assert_eq!(code(&p), (b'M', 117));
    assert_eq!(p.text, Some(&b"text X1 (y)"[..]));
    assert!(p.words().is_empty());
    assert_eq!(p.comment, Some(&b" with semicolons; more"[..]));
    assert!(p.diags().is_empty());
    let p = parse_line(b"M118 E1 hello");
    assert_eq!(p.text, Some(&b"E1 hello"[..]));
}

#[test]
fn m486_object_labels_are_text() {
    for line in [
        &b"M486 Acylinder_d40.stl"[..],
        b"M486 S0",
        b"M486 S-1",
        b"M486 T3",
    ] {
        let p = parse_line(line);
        assert_eq!(code(&p), (b'M', 486));
        assert!(p.diags().is_empty(), "{line:?}");
    }
}

#[test]
fn exponent_e_starts_an_e_word_with_a_warning() {
    let p = parse_line(b"G1 F1.2e3");
    assert_eq!(words(&p), vec![('F', Some(1.2), 4), ('E', Some(3.0), 8)]);
    assert_eq!(p.diags().len(), 1);
    assert_eq!(p.diags()[0].kind, DiagKind::ExponentReadAsE);
    assert_eq!(p.diags()[0].column, 8);
    // With a space it is an ordinary E word.
    assert!(parse_line(b"G1 F1.2 E3").diags().is_empty());
}

#[test]
fn letters_without_values() {
    let p = parse_line(b"G28 X Y");
    assert_eq!(code(&p), (b'G', 28));
    assert_eq!(words(&p), vec![('X', None, 5), ('Y', None, 7)]);
    assert!(p.diags().is_empty());
}

#[test]
fn inline_paren_comment() {
    let p = parse_line(b"G1 (move) X1 (fast)");
    assert_eq!(words(&p), vec![('X', Some(1.0), 11)]);
    assert_eq!(p.comment, Some(&b"move"[..]));
    let p = parse_line(b"G1 X1 (open");
    assert_eq!(p.diags()[0].kind, DiagKind::UnclosedParen);
}

#[test]
fn lowercase_and_leading_point() {
    let p = parse_line(b"g1 x-.5 y+.25 e.1");
    assert_eq!(code(&p), (b'G', 1));
    assert_eq!(
        words(&p),
        vec![
            ('X', Some(-0.5), 4),
            ('Y', Some(0.25), 9),
            ('E', Some(0.1), 15)
        ]
    );
    assert!(p.diags().is_empty());
}

#[test]
fn compact_words_without_spaces() {
    let p = parse_line(b"G1X10Y-2.5Z.3");
    assert_eq!(code(&p), (b'G', 1));
    assert_eq!(
        words(&p),
        vec![
            ('X', Some(10.0), 3),
            ('Y', Some(-2.5), 6),
            ('Z', Some(0.3), 11)
        ]
    );
}

#[test]
fn crlf_and_non_utf8_comment() {
    let p = parse_line(b"G1 X1 ; caf\xe9 \xff\r\n");
    assert_eq!(p.value(b'X'), Some(1.0));
    assert_eq!(p.comment, Some(&b" caf\xe9 \xff"[..]));
    assert!(p.diags().is_empty());
}

#[test]
fn thumbnail_lines_are_comments() {
    for l in [
        &b"; thumbnail begin 16x16 520\n"[..],
        b"; iVBORw0KGgoAAAANSUhEUgAAABAAAAAQCAYAAAAf8/9hAAAA+0lEQVR4nGNgGAWjYBSMglEw\n",
        b"; thumbnail end\n",
    ] {
        let p = parse_line(l);
        assert_eq!(p.command, Command::None);
        assert!(p.comment.is_some() && p.diags().is_empty());
    }
}

#[test]
fn extended_commands() {
    let p = parse_line(b"SET_VELOCITY_LIMIT ACCEL=3000");
    assert!(
        matches!(p.command, Command::Extended { name, column: 1 } if name == b"SET_VELOCITY_LIMIT")
    );
    let a = p.param("accel").unwrap();
    assert_eq!((a.value, a.column), (&b"3000"[..], 20));
    assert_eq!(param_f64(a.value), Some(3000.0));

    let p = parse_line(b"EXCLUDE_OBJECT_DEFINE NAME=a CENTER=1,2 POLYGON=[[0,0],[1,1]] ; c\n");
    assert!(
        matches!(p.command, Command::Extended { name, .. } if name == b"EXCLUDE_OBJECT_DEFINE")
    );
    let kv: Vec<(&[u8], &[u8])> = p.params().map(|p| (p.key, p.value)).collect();
    assert_eq!(
        kv,
        vec![
            (&b"NAME"[..], &b"a"[..]),
            (b"CENTER", b"1,2"),
            (b"POLYGON", b"[[0,0],[1,1]]")
        ]
    );
    assert_eq!(param_f64(b"1,2"), None);
    let p = parse_line(b"exclude_object_start NAME=\"my part.stl\"");
    assert_eq!(p.param("NAME").unwrap().value, b"my part.stl");
    let p = parse_line(b"EXCLUDE_OBJECT_END NAME='plate 1'");
    assert_eq!(p.param("NAME").unwrap().value, b"plate 1");
    let p = parse_line(b"PRINT_START OOPS EXTRUDER=210");
    assert_eq!(p.diags()[0].kind, DiagKind::ExpectedKeyValue);
    assert_eq!(p.diags()[0].column, 13);
    assert_eq!(p.param("EXTRUDER").unwrap().value, b"210");
}

#[test]
fn helix_arc_line() {
    let p = parse_line(b"G3 X0 Y-98 I98 Z0.2 E40");
    assert_eq!(code(&p), (b'G', 3));
    assert_eq!(
        words(&p),
        vec![
            ('X', Some(0.0), 4),
            ('Y', Some(-98.0), 7),
            ('I', Some(98.0), 12),
            ('Z', Some(0.2), 16),
            ('E', Some(40.0), 21)
        ]
    );
}

#[test]
fn malformed_number_in_motion_is_an_error_with_column() {
    let p = parse_line(b"G1 X1.2.3 Y4");
    assert_eq!(
        p.diags(),
        &[LineDiag {
            column: 5,
            severity: Severity::Error,
            kind: DiagKind::MalformedNumber
        }]
    );
    assert!(p.has_error());
    assert_eq!(p.word(b'X').unwrap().value, None);
    assert_eq!(p.value(b'Y'), Some(4.0));
    for bad in [&b"G1 X-"[..], b"G0 Y.", b"G1 X1:2", b"G1 X+-1"] {
        assert!(parse_line(bad).has_error(), "{:?}", bad);
    }
    // Elsewhere it is a warning.
    let p = parse_line(b"M106 S1.2.3");
    assert_eq!(p.diags()[0].severity, Severity::Warning);
    // Out of range (no overflow to infinity).
    let big = format!("G1 X{}", "9".repeat(400));
    let p = parse_line(big.as_bytes());
    assert!(p.has_error());
    assert_eq!(p.diags()[0].kind, DiagKind::NumberOutOfRange);
    assert_eq!(p.diags()[0].column, 5);
    assert!(p.diags()[0].message().contains("out of range"));
    assert_eq!(
        parse_line(b"G1 X1000000001").diags()[0].kind,
        DiagKind::NumberOutOfRange
    );
    assert!(parse_line(b"G1 X999999999").diags().is_empty());
}

#[test]
fn unexpected_characters_and_duplicates() {
    let p = parse_line(b"G1 X1 # Y2 X3");
    assert_eq!(p.diags()[0].kind, DiagKind::UnexpectedChar(b'#'));
    assert_eq!(p.diags()[0].column, 7);
    assert_eq!(p.diags()[1].kind, DiagKind::DuplicateWord(b'X'));
    assert_eq!(p.value(b'X'), Some(3.0));
}

#[test]
fn each_letters_word_is_the_last_one_kept() {
    // Duplicates, words without values, lower case, a comment between, more words than
    // kept (the 17th and later are dropped, a letter among them included), an extended
    // command and a blank line: `word` answers what a search of the words from the end does.
    let many: String = (0..20)
        .map(|i| format!(" {}{i}", char::from(b'A' + i % 7)))
        .collect();
    let lines = [
        "G1 X1 Y2 X3 E.5 F1200".to_string(),
        "G28 X Y z7 (note) Z8".to_string(),
        format!("G1{many} W9"),
        "SET_VELOCITY_LIMIT ACCEL=3000".to_string(),
        String::new(),
    ];
    for line in &lines {
        let p = parse_line(line.as_bytes());
        for letter in (b'@'..=b'z').chain([0, b'*', 255]) {
            let search = p.words().iter().rev().find(|w| w.letter == letter);
            assert_eq!(p.word(letter), search, "{line:?} {}", char::from(letter));
        }
    }
}

#[test]
fn short_decimals_match_fast_float() {
    // Against fast-float2 (correctly rounded), over many shapes of numbers.
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let int = x % 1_000_000;
        let frac_digits = (x >> 20) % 10;
        let frac = (x >> 24) % 10u64.pow(frac_digits as u32);
        let sign = ["", "-", "+"][((x >> 40) % 3) as usize];
        let t = if frac_digits == 0 {
            format!("{sign}{int}")
        } else {
            format!("{sign}{int}.{frac:0w$}", w = frac_digits as usize)
        };
        let want: f64 = fast_float2::parse(t.as_bytes()).unwrap();
        assert_eq!(number(t.as_bytes()), (&b""[..], Some(want)), "{t}");
    }
    assert_eq!(number(b".5 X"), (&b" X"[..], Some(0.5)));
    assert_eq!(number(b"-.25"), (&b""[..], Some(-0.25)));
    assert_eq!(number(b"7.Y"), (&b"Y"[..], Some(7.0)));
    assert_eq!(number(b"-"), (&b""[..], None));
    assert_eq!(number(b"."), (&b""[..], None));
    assert_eq!(number(b"1.2.3"), (&b".3"[..], Some(1.2)));
    assert_eq!(number(b"1234567890123456").1, None); // out of range
    assert_eq!(
        number(b"0.1234567890123456789").1,
        "0.1234567890123456789".parse::<f64>().ok()
    );
}

#[test]
fn blank_and_comment_lines() {
    assert_eq!(parse_line(b"\n").command, Command::None);
    assert_eq!(parse_line(b"   \t\r\n").command, Command::None);
    let p = parse_line(b"  ;LAYER:3\n");
    assert_eq!(p.command, Command::None);
    assert_eq!(p.comment, Some(&b"LAYER:3"[..]));
    let p = parse_line(b"G29.1 X1");
    assert!(matches!(
        p.command,
        Command::Code {
            letter: b'G',
            number: 29,
            subcode: Some(1),
            ..
        }
    ));
}
