//! Planner moves/s, model samples/s (one `evaluate`; a block of states through the
//! vectorised forces), and resample + model + statistics samples/s (`check`'s per-move code), on
//! the shipped Cura calibration cube and the Kossel profile.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use delta_gcode::analysis::{MoveChecker, Scratch, sequence};
use delta_gcode::delta::{BLOCK, ForceBlock, StateBlock};
use delta_gcode::firmware::klipper::planner::{PlannedMove, Planner};
use delta_gcode::gcode::{ArcRules, Event, interpret};
use delta_gcode::machine::Machine;
use delta_gcode::path::Vec3;

fn repo(p: &str) -> String {
    format!("{}/{p}", env!("CARGO_MANIFEST_DIR"))
}

fn setup() -> (Machine, Vec<Event>) {
    let machine = Machine::load(Path::new(&repo("machines/kossel.yaml"))).expect("profile");
    let data = std::fs::read(repo("samples/calib-cube_cura413_kossel-mini.gcode")).expect("sample");
    let mut events = Vec::new();
    let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
    interpret(
        &data[..],
        home,
        ArcRules::default(),
        |e| events.push(e),
        |_| {},
    )
    .expect("read");
    (machine, events)
}

fn plan(machine: &Machine, events: &[Event]) -> Vec<PlannedMove> {
    let mut planner = Planner::new(machine);
    let mut out = Vec::new();
    for e in events {
        planner.push(e, &mut |m| out.push(m));
    }
    planner.finish(&mut |m| out.push(m));
    out
}

fn bench(c: &mut Criterion) {
    let (machine, events) = setup();
    let moves = plan(&machine, &events);
    let model = machine.model();

    let mut g = c.benchmark_group("planner");
    g.throughput(Throughput::Elements(moves.len() as u64));
    g.bench_function("plan_cube", |b| {
        b.iter(|| black_box(plan(&machine, &events).len()))
    });
    g.finish();

    // One model evaluation: a nozzle state in the print volume, accelerating.
    let mut g = c.benchmark_group("model");
    g.throughput(Throughput::Elements(1));
    let (p, v, a) = (
        Vec3::new(30.0, -20.0, 5.0),
        Vec3::new(120.0, 80.0, 0.0),
        Vec3::new(2000.0, -1500.0, 0.0),
    );
    g.bench_function("evaluate", |b| {
        b.iter(|| black_box(model.evaluate(black_box(p), black_box(v), black_box(a))))
    });

    // The vectorised forces over a full block of states (what `check` runs), per state.
    let mut states = StateBlock::default();
    for j in 0..BLOCK {
        let s = j as f64 / BLOCK as f64;
        for k in 0..3 {
            states.pos_mm[k][j] = p[k] * (1.0 - s);
            states.vel_mm_s[k][j] = v[k] * s;
            states.acc_mm_s2[k][j] = a[k] * (0.5 - s);
        }
    }
    let mut forces = ForceBlock::default();
    g.throughput(Throughput::Elements(BLOCK as u64));
    g.bench_function("forces_block", |b| {
        b.iter(|| {
            model.forces_block(black_box(&states), BLOCK, &mut forces);
            black_box(forces.force_n[0][0])
        })
    });
    g.finish();

    // The sequential stages (shaper, drive) into one batch; then the sampling, the model
    // and the statistics over it, on one thread: `check`'s own per-move code.
    let data = std::fs::read(repo("samples/calib-cube_cura413_kossel-mini.gcode")).expect("sample");
    let mut batch = None;
    sequence(&data[..], &machine, usize::MAX, |_| {}, |b| batch = Some(b)).expect("read");
    let batch = batch.expect("a batch");
    let checker = MoveChecker::new(&machine, ());
    let mut scratch = Box::<Scratch>::default();
    let mut out = Vec::new();
    checker.check_moves(&mut scratch, &batch.pieces, &batch.moves, &mut out);
    let samples: u64 = out.iter().map(|r| r.stats.samples).sum();
    let mut g = c.benchmark_group("resample_and_model");
    g.throughput(Throughput::Elements(samples));
    g.sample_size(10);
    g.bench_function("cube", |b| {
        b.iter(|| {
            let mut out = Vec::with_capacity(batch.moves.len());
            checker.check_moves(&mut scratch, &batch.pieces, &batch.moves, &mut out);
            let peak = out
                .iter()
                .map(|r| r.stats.peak_force_n[0])
                .fold(0.0, f64::max);
            black_box(peak)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
