//! Is this G-code at all? The first bytes of an input tell a compressed file, a 3D model,
//! PrusaSlicer's binary G-code or other binary data from text, so that a CI gate fed the
//! wrong file stops with an input error instead of finding "0 moves, all within the limits".
//!
//! Text G-code is never refused here: a text file that holds no move is found later, by
//! the analysis (no motion).

use std::fmt;

/// How many bytes of the input [`sniff`] looks at.
pub const SNIFF_BYTES: usize = 8192;

/// What an input that is not text G-code is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotGcode {
    Gzip,
    Xz,
    Zstd,
    Bzip2,
    /// A zip archive that is not a 3MF project.
    Zip,
    /// A 3MF project (a zip archive holding `3D/3dmodel.model`).
    ThreeMf,
    /// An ASCII STL (`solid …` then `facet normal …`).
    StlAscii,
    /// A binary STL (80-byte header, a triangle count, 50 bytes a triangle).
    StlBinary,
    /// PrusaSlicer's binary G-code (libbgcode, magic `GCDE`).
    BinaryGcode,
    /// Other bytes that are not text (NUL bytes, many control characters).
    Binary,
}

/// Says what `head` (the first [`SNIFF_BYTES`] bytes of an input of `len` bytes, when the
/// length is known) is, when it is not text G-code.
pub fn sniff(head: &[u8], len: Option<u64>) -> Option<NotGcode> {
    let starts = |magic: &[u8]| head.starts_with(magic);
    if starts(b"GCDE") {
        return Some(NotGcode::BinaryGcode);
    }
    if starts(&[0x1f, 0x8b]) {
        return Some(NotGcode::Gzip);
    }
    if starts(&[0xfd, b'7', b'z', b'X', b'Z', 0x00]) {
        return Some(NotGcode::Xz);
    }
    if starts(&[0x28, 0xb5, 0x2f, 0xfd]) {
        return Some(NotGcode::Zstd);
    }
    if starts(b"BZh") && head.get(3).is_some_and(|c| (b'1'..=b'9').contains(c)) {
        return Some(NotGcode::Bzip2);
    }
    if starts(b"PK\x03\x04") || starts(b"PK\x05\x06") {
        let model = contains(head, b"3D/3dmodel.model") || contains(head, b"3D/3DModel.model");
        return Some(if model {
            NotGcode::ThreeMf
        } else {
            NotGcode::Zip
        });
    }
    // A binary STL's header is free text (often "solid …" too): its length tells it.
    if let (Some(len), Some(count)) = (len, head.get(80..84)) {
        let triangles = u32::from_le_bytes([count[0], count[1], count[2], count[3]]);
        if len >= 84 + 50 && len == 84 + 50 * u64::from(triangles) {
            return Some(NotGcode::StlBinary);
        }
    }
    let text = head.trim_ascii_start();
    if text.len() >= 5
        && text[..5].eq_ignore_ascii_case(b"solid")
        && (contains(head, b"facet") || contains(head, b"endsolid"))
    {
        return Some(NotGcode::StlAscii);
    }
    let control = head
        .iter()
        .filter(|&&c| (c < 0x20 && !matches!(c, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c)) || c == 0x7f)
        .count();
    // G-code is text: a NUL byte, or more than one byte in 20 a control character, is not.
    if head.contains(&0) || control * 20 > head.len() {
        return Some(NotGcode::Binary);
    }
    None
}

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

impl NotGcode {
    /// What the input is, in a few words ("gzip-compressed", "an STL model (binary)").
    pub fn what(self) -> &'static str {
        match self {
            NotGcode::Gzip => "gzip-compressed",
            NotGcode::Xz => "xz-compressed",
            NotGcode::Zstd => "zstd-compressed",
            NotGcode::Bzip2 => "bzip2-compressed",
            NotGcode::Zip => "a zip archive",
            NotGcode::ThreeMf => "a 3MF project (a 3D model)",
            NotGcode::StlAscii => "an STL model (ASCII)",
            NotGcode::StlBinary => "an STL model (binary)",
            NotGcode::BinaryGcode => "PrusaSlicer binary G-code (.bgcode)",
            NotGcode::Binary => "binary data",
        }
    }

    /// What to do about it, for the input named `name`.
    pub fn advice(self, name: &str) -> String {
        match self {
            NotGcode::Gzip => format!(
                "decompress it first: `gunzip -k {name}`, or `gunzip -c {name} | delta-gcode check - -m M.yaml`"
            ),
            NotGcode::Xz => format!(
                "decompress it first: `xz -dk {name}`, or `xz -dc {name} | delta-gcode check - -m M.yaml`"
            ),
            NotGcode::Zstd => format!("decompress it first: `zstd -d {name}`"),
            NotGcode::Bzip2 => format!("decompress it first: `bunzip2 -k {name}`"),
            NotGcode::Zip => format!("extract the G-code first: `unzip {name}`"),
            NotGcode::ThreeMf | NotGcode::StlAscii | NotGcode::StlBinary => {
                "slice it first and check the G-code the slicer exports".to_string()
            }
            NotGcode::BinaryGcode => "delta-gcode reads text G-code. In PrusaSlicer turn binary \
                 G-code off: Printer Settings → General → Firmware → \"Supports binary G-code\" \
                 (binary_gcode = 0), or for every printer Configuration → Preferences → Other → \
                 \"Use binary G-code when the printer supports it\"; or convert this file with \
                 File → Convert → Convert binary G-code"
                .to_string(),
            NotGcode::Binary => "is it the file you meant? delta-gcode reads the text G-code \
                 a slicer exports"
                .to_string(),
        }
    }

    /// The whole message for the input named `name`: what it is and what to do.
    pub fn message(self, name: &str) -> String {
        format!(
            "{name} is {}, not G-code: {}",
            self.what(),
            self.advice(name)
        )
    }
}

impl fmt::Display for NotGcode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.what())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary_stl(triangles: u32, header: &[u8]) -> Vec<u8> {
        let mut v = header.to_vec();
        v.resize(80, b' ');
        v.extend_from_slice(&triangles.to_le_bytes());
        v.resize(84 + 50 * triangles as usize, 0);
        v
    }

    #[test]
    fn text_gcode_passes() {
        for g in [
            &b"G28\nG1 X10 Y10 F3000\n"[..],
            b"; generated by PrusaSlicer 2.5.0\n; thumbnail begin 16x16 520\n; iVBORw0KGgo=\n",
            b"\xef\xbb\xbfG1 X1 ; caf\xc3\xa9\r\n",
            b"",
            b"; only a comment\n",
            b"SOLID_MACRO X=1\n",
        ] {
            assert_eq!(sniff(g, Some(g.len() as u64)), None, "{g:?}");
        }
    }

    #[test]
    fn compressed_archives_and_models_are_told_apart() {
        let cases: [(&[u8], NotGcode); 8] = [
            (&[0x1f, 0x8b, 8, 0, 0, 0], NotGcode::Gzip),
            (b"\xfd7zXZ\x00\x00\x04", NotGcode::Xz),
            (&[0x28, 0xb5, 0x2f, 0xfd, 0], NotGcode::Zstd),
            (b"BZh91AY&SY", NotGcode::Bzip2),
            (b"PK\x03\x04\x14\x00\x00\x00readme.txt", NotGcode::Zip),
            (
                b"PK\x03\x04\x14\x00\x00\x00\x08\x003D/3dmodel.model",
                NotGcode::ThreeMf,
            ),
            (
                b"solid cylinder\n  facet normal 0 0 1\n    outer loop\n",
                NotGcode::StlAscii,
            ),
            (b"GCDE\x01\x00\x00\x00\x01\x00", NotGcode::BinaryGcode),
        ];
        for (bytes, want) in cases {
            assert_eq!(sniff(bytes, Some(bytes.len() as u64)), Some(want));
        }
    }

    #[test]
    fn a_binary_stl_is_known_by_its_length_even_when_its_header_says_solid() {
        let stl = binary_stl(3, b"solid exported by a CAD program");
        let head = &stl[..stl.len().min(SNIFF_BYTES)];
        assert_eq!(
            sniff(head, Some(stl.len() as u64)),
            Some(NotGcode::StlBinary)
        );
        // One byte more and it is not an STL: then its NUL bytes make it binary.
        assert_eq!(
            sniff(head, Some(stl.len() as u64 + 1)),
            Some(NotGcode::Binary)
        );
    }

    #[test]
    fn control_characters_and_nul_are_binary() {
        assert_eq!(sniff(b"G1 X1\0\n", None), Some(NotGcode::Binary));
        let noise: Vec<u8> = (0..200u8).map(|i| i.wrapping_mul(37) % 32).collect();
        assert_eq!(sniff(&noise, None), Some(NotGcode::Binary));
    }

    #[test]
    fn messages_name_the_file_and_what_to_do() {
        let m = NotGcode::Gzip.message("part.gcode.gz");
        assert!(
            m.starts_with("part.gcode.gz is gzip-compressed, not G-code: "),
            "{m}"
        );
        assert!(m.contains("gunzip -k part.gcode.gz"), "{m}");
        let m = NotGcode::StlBinary.message("cube.stl");
        assert!(
            m.starts_with("cube.stl is an STL model (binary), not G-code: slice it"),
            "{m}"
        );
        let m = NotGcode::BinaryGcode.message("a.bgcode");
        assert!(m.contains("binary_gcode = 0"), "{m}");
    }
}
