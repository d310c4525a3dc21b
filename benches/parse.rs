//! Parse-only throughput on real slicer lines (fixtures repeated to a few MB), against
//! line splitting alone, and the whole interpreter over the same bytes. With
//! `DELTA_GCODE_BENCH_FILE=path` the same three run on that file instead (e.g. the 27.8 MB
//! bunny of the corpus), read into memory first.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use delta_gcode::gcode::{ArcRules, LineReader, interpret, parse_line};
use delta_gcode::path::Vec3;

fn corpus() -> Vec<u8> {
    if let Some(path) = std::env::var_os("DELTA_GCODE_BENCH_FILE") {
        return std::fs::read(&path).expect("DELTA_GCODE_BENCH_FILE names a readable file");
    }
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/");
    let mut one = Vec::new();
    for f in ["ps25_bunny_head.gcode", "ps29_arcs_exclude.gcode"] {
        one.extend(std::fs::read(format!("{dir}{f}")).unwrap_or_default());
    }
    let mut data = Vec::with_capacity(4 << 20);
    while !one.is_empty() && data.len() < 4 << 20 {
        data.extend_from_slice(&one);
    }
    data
}

fn bench(c: &mut Criterion) {
    let data = corpus();
    let mut g = c.benchmark_group("gcode");
    g.throughput(Throughput::Bytes(data.len() as u64));
    if data.len() > 16 << 20 {
        g.sample_size(10); // a tenth of a second per pass
    }
    g.bench_function("split_lines", |b| {
        b.iter(|| {
            let mut r = LineReader::new(&data[..]);
            let mut n = 0usize;
            while let Ok(Some(l)) = r.next_line() {
                n += l.bytes.len();
            }
            black_box(n)
        })
    });
    g.bench_function("split_and_parse", |b| {
        b.iter(|| {
            let mut r = LineReader::new(&data[..]);
            let mut n = 0usize;
            while let Ok(Some(l)) = r.next_line() {
                n += parse_line(l.bytes).words().len();
            }
            black_box(n)
        })
    });
    g.bench_function("interpret", |b| {
        b.iter(|| {
            let mut n = 0usize;
            let stats = interpret(
                &data[..],
                Vec3::new(0.0, 0.0, 290.0),
                ArcRules::default(),
                |_| n += 1,
                |_| {},
            );
            black_box((n, stats.ok()))
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
