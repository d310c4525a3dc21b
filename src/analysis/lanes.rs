//! Where the pipeline's stages run: two lanes that share the drive stage and the model
//! stage's batches, so that neither core waits while the other has work (issue 17).
//!
//! The firmware lane (the calling thread) reads, interprets and plans, and hands its
//! commanded pieces on in steps. The model lane (a thread of its own) takes the oldest
//! batch of work to check first, then the drive stage's next step. The firmware lane takes
//! the drive stage's steps itself when they pile up (the model lane is behind), and a
//! batch, or the chunks of the batch being checked, when the batches in flight are full.
//! So the drive stage runs where there is room: with the firmware when the model is the
//! larger stage (Klipper without an input shaper), with the model when the firmware is
//! (with a shaper, Marlin's segments). Before, each stage had a thread of its own, and four
//! threads on two cores waited on each other (docs/performance.md, "Sixteenth session").
//!
//! The drive stage and the model stage each run on one lane at a time, their steps and
//! batches taken in order, so the results are those of a single thread, bit for bit.

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

use super::crew::Crew;
use super::sequence::{Batch, Checked, Sequencer};
use super::{Job, ModelStage, MoveResult, Observer};
use crate::motion::Segment;

/// The checks and commanded pieces handed from the firmware to the drive stage at a time:
/// the checks of a step's moves come before its pieces, as each move's checks come before
/// its own pieces (the planner only delays pieces).
#[derive(Default)]
pub(super) struct Steps {
    pub checked: Vec<Checked>,
    pub commanded: Vec<Segment>,
}

/// Commanded pieces, or checks, in a step (see [`Steps`]): the planner's lookahead may hold
/// thousands of moves' checks before their pieces come.
pub(super) const STEP_PIECES: usize = 1024;

/// Steps waiting for the drive stage before the firmware lane takes them itself, and the
/// most that wait (the firmware lane then waits too): about a batch, so that the model lane
/// can check one while the firmware goes on, and the memory stays bounded (1.7 MB of
/// pieces at most).
const STEPS_AHEAD: usize = 8;
const STEPS_IN_FLIGHT: usize = 16;

/// Batches made and not yet checked: bounds the memory.
const BATCHES_IN_FLIGHT: usize = 2;

/// What the lanes share, under one lock.
#[derive(Default)]
struct State {
    steps: VecDeque<Steps>,
    spare_steps: Vec<Steps>,
    batches: VecDeque<Batch>,
    spare_batches: Vec<Batch>,
    /// The firmware has handed on its last step.
    read_done: bool,
    /// A lane is in the drive stage, in the model stage.
    drive_busy: bool,
    model_busy: bool,
    /// The drive stage has made its last batch; the model stage has handed on its last
    /// result.
    drive_done: bool,
    model_done: bool,
    /// A lane stopped by a panic: the others stop too (the panic is raised again where the
    /// lanes are joined).
    failed: bool,
    /// Lanes waiting for a change.
    waiting: usize,
}

/// A piece of work a lane takes.
enum Task {
    Drive(Steps),
    Finish,
    Model(Batch),
    Last,
}

/// The drive stage's side: the sequencer and the batch size.
pub(super) struct Drive {
    pub sequencer: Sequencer,
    pub batch_pieces: usize,
}

/// The model stage's side: its state, and where its results go.
pub(super) struct Model<'c, 'm, O: Observer, F> {
    pub stage: ModelStage<'c, 'm, O>,
    pub on_move: F,
}

/// The two lanes' shared state and stages.
pub(super) struct Lanes<'c, 'm, O: Observer, F, W> {
    state: Mutex<State>,
    changed: Condvar,
    drive: Mutex<Drive>,
    model: Mutex<Model<'c, 'm, O, F>>,
    crew: &'c Crew<Job<O::PerMove>>,
    work: &'c W,
}

impl<'c, 'm, O, F, W> Lanes<'c, 'm, O, F, W>
where
    O: Observer,
    F: FnMut(&mut MoveResult<O::PerMove>) + Send,
    W: Fn(&Job<O::PerMove>, usize) + Sync,
{
    pub fn new(
        drive: Drive,
        model: Model<'c, 'm, O, F>,
        crew: &'c Crew<Job<O::PerMove>>,
        work: &'c W,
    ) -> Self {
        Lanes {
            state: Mutex::default(),
            changed: Condvar::new(),
            drive: Mutex::new(drive),
            model: Mutex::new(model),
            crew,
            work,
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Wakes the lanes waiting for a change, if any (a wake-up is a system call).
    fn changed(&self, state: &State) {
        if state.waiting > 0 {
            self.changed.notify_all();
        }
    }

    /// Changes the shared state, and wakes the lanes waiting for a change.
    fn update(&self, change: impl FnOnce(&mut State)) {
        let mut state = self.lock();
        change(&mut state);
        self.changed(&state);
    }

    /// Waits for a change; the lock is given up meanwhile.
    fn wait<'a>(&self, mut state: MutexGuard<'a, State>) -> MutexGuard<'a, State> {
        state.waiting += 1;
        let mut state = self
            .changed
            .wait(state)
            .unwrap_or_else(PoisonError::into_inner);
        state.waiting -= 1;
        state
    }

    /// An emptied step to fill (the firmware lane's).
    pub fn spare_step(&self) -> Steps {
        self.lock().spare_steps.pop().unwrap_or_default()
    }

    /// The firmware lane hands on a step (`last`: its final one). When the steps pile up it
    /// takes work itself, and waits while they are at their most and no work is to be had.
    pub fn push_step(&self, step: Steps, last: bool) {
        let mut state = self.lock();
        if state.failed {
            return;
        }
        state.steps.push_back(step);
        state.read_done = last;
        self.changed(&state);
        while !state.failed && state.steps.len() >= STEPS_AHEAD {
            let task = self.firmware_task(&mut state);
            let did;
            (state, did) = self.take(state, task);
            if !did {
                if state.steps.len() < STEPS_IN_FLIGHT || state.failed {
                    break;
                }
                state = self.wait(state);
            }
        }
    }

    /// What the firmware lane takes when the steps pile up: the drive stage's next step
    /// while the batches are not at their most, else the oldest batch.
    fn firmware_task(&self, state: &mut State) -> Option<Task> {
        self.drive_task(state).or_else(|| self.model_task(state))
    }

    /// The model lane's loop, and the firmware lane's after its last step: the oldest
    /// batch first, then the drive stage, then a part of the batch being checked, until
    /// the last result is handed on.
    pub fn work(&self) {
        let _guard = self.guard();
        let mut state = self.lock();
        while !state.model_done && !state.failed {
            let task = self
                .model_task(&mut state)
                .or_else(|| self.drive_task(&mut state));
            let did;
            (state, did) = self.take(state, task);
            if !did && !state.model_done && !state.failed {
                state = self.wait(state);
            }
        }
    }

    /// Does `task`, or without one a part of the batch being checked, the lock given up
    /// meanwhile; whether there was anything to do.
    fn take<'a>(
        &'a self,
        state: MutexGuard<'a, State>,
        task: Option<Task>,
    ) -> (MutexGuard<'a, State>, bool) {
        drop(state);
        let did = match task {
            Some(task) => {
                self.run(task);
                true
            }
            None => self.crew.claim(self.work),
        };
        (self.lock(), did)
    }

    /// The model stage's next task, if no lane is in it: the oldest batch, or the last
    /// result once the drive stage has made every batch.
    fn model_task(&self, state: &mut State) -> Option<Task> {
        if state.model_busy || state.model_done {
            return None;
        }
        let task = match state.batches.pop_front() {
            Some(batch) => Task::Model(batch),
            None if state.drive_done => Task::Last,
            None => return None,
        };
        state.model_busy = true;
        Some(task)
    }

    /// The drive stage's next task, if no lane is in it and the batches are not at their
    /// most: the oldest step, or the end of the motion after the last one.
    fn drive_task(&self, state: &mut State) -> Option<Task> {
        if state.drive_busy || state.drive_done || state.batches.len() >= BATCHES_IN_FLIGHT {
            return None;
        }
        let task = match state.steps.pop_front() {
            Some(step) => Task::Drive(step),
            None if state.read_done => Task::Finish,
            None => return None,
        };
        state.drive_busy = true;
        self.changed(state);
        Some(task)
    }

    fn run(&self, task: Task) {
        match task {
            Task::Drive(step) => self.drive_step(step),
            Task::Finish => self.finish_drive(),
            Task::Model(batch) => self.check_batch(batch),
            Task::Last => self.last_result(),
        }
    }

    /// The drive stage over one step: its batches handed on as they fill.
    fn drive_step(&self, mut step: Steps) {
        let mut drive = self.drive.lock().unwrap_or_else(PoisonError::into_inner);
        let Drive {
            sequencer,
            batch_pieces,
        } = &mut *drive;
        sequencer.checked(&mut step.checked);
        sequencer.drive(
            &step.commanded,
            *batch_pieces,
            &mut || self.lock().spare_batches.pop(),
            &mut |batch| self.update(|state| state.batches.push_back(batch)),
        );
        step.commanded.clear();
        self.update(|state| {
            state.spare_steps.push(step);
            state.drive_busy = false;
        });
    }

    /// The end of the motion: the drive's settling, the last batch.
    fn finish_drive(&self) {
        let mut drive = self.drive.lock().unwrap_or_else(PoisonError::into_inner);
        drive.sequencer.finish();
        let batch = drive.sequencer.take_batch(true);
        self.update(|state| {
            state.batches.push_back(batch);
            state.drive_busy = false;
            state.drive_done = true;
        });
    }

    /// The model stage over one batch, its chunks shared with whoever is free.
    fn check_batch(&self, batch: Batch) {
        let mut model = self.model.lock().unwrap_or_else(PoisonError::into_inner);
        let Model { stage, on_move } = &mut *model;
        let posted = || self.update(|_| {});
        let batch = stage.process(self.crew, self.work, batch, on_move, posted);
        self.update(|state| {
            state.spare_batches.push(batch);
            state.model_busy = false;
        });
    }

    /// The last line's result, held back in case the next batch went on with it.
    fn last_result(&self) {
        let mut model = self.model.lock().unwrap_or_else(PoisonError::into_inner);
        let Model { stage, on_move } = &mut *model;
        if let Some(mut last) = stage.pending.take() {
            on_move(&mut last);
        }
        self.update(|state| {
            state.model_busy = false;
            state.model_done = true;
        });
    }

    /// The drive stage, once the lanes are done.
    pub fn into_drive(self) -> Drive {
        self.drive
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// A guard that stops the other lanes if this one panics while it is held.
    pub fn guard(&self) -> FailGuard<'_, 'c, 'm, O, F, W> {
        FailGuard(self)
    }

    /// Stops the lanes (a lane panicked).
    fn fail(&self) {
        let mut state = self.lock();
        state.failed = true;
        self.changed.notify_all();
        drop(state);
    }
}

/// Stops the other lanes when a lane panics: they would wait for it for ever.
pub(super) struct FailGuard<'a, 'c, 'm, O: Observer, F, W>(&'a Lanes<'c, 'm, O, F, W>)
where
    F: FnMut(&mut MoveResult<O::PerMove>) + Send,
    W: Fn(&Job<O::PerMove>, usize) + Sync;

impl<O: Observer, F, W> Drop for FailGuard<'_, '_, '_, O, F, W>
where
    F: FnMut(&mut MoveResult<O::PerMove>) + Send,
    W: Fn(&Job<O::PerMove>, usize) + Sync,
{
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.fail();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{RunPeaks, pass_on, run_on};
    use crate::gcode::Event;
    use crate::machine::test_support::kossel_machine;
    use crate::report::MoveStats;
    use std::panic::{AssertUnwindSafe, catch_unwind};
    use std::sync::mpsc;
    use std::time::Duration;

    /// The Cura cube: 8,716 moves, several batches.
    fn cube() -> Vec<u8> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/samples/calib-cube_cura413_kossel-mini.gcode"
        );
        std::fs::read(path).expect("sample")
    }

    /// Every line's statistics, in the order they came, on `threads` threads.
    fn results(gcode: &[u8], threads: usize, peaks_only: bool) -> Vec<(u64, MoveStats)> {
        let machine = kossel_machine();
        let mut out = Vec::new();
        let on_move = |r: &mut super::super::MoveResult<()>| out.push((r.group, r.stats.clone()));
        let totals = if peaks_only {
            run_on(
                gcode,
                &machine,
                RunPeaks(()),
                &mut pass_on,
                on_move,
                |_| {},
                threads,
            )
        } else {
            run_on(gcode, &machine, (), &mut pass_on, on_move, |_| {}, threads)
        };
        assert!(totals.expect("reads").print_time_s > 0.0);
        out
    }

    /// The run's peaks over every line's statistics, the samples counted, and the lines
    /// flagged: what a report shows without the list of moves. (Not the carriages' peak
    /// speed: a report does not show it, and against the run's peaks a move let go whole
    /// adds none, so it depends on which moves the floor let go when. Compared, it failed
    /// once in 40 runs under load.)
    fn peaks(results: &[(u64, MoveStats)]) -> (Vec<f64>, u64, Vec<u64>) {
        let mut peaks = vec![0.0; 9];
        for (_, s) in results {
            for i in 0..3 {
                peaks[i] = s.peak_force_n[i].max(peaks[i]);
                peaks[3 + i] = s.peak_tension_n[i].max(peaks[3 + i]);
                peaks[6 + i] = s.worst[i].ratio.max(peaks[6 + i]);
            }
        }
        let samples = results.iter().map(|(_, s)| s.samples).sum();
        let flagged = results
            .iter()
            .filter(|(_, s)| s.over_force() || s.checks.problem.is_some())
            .map(|(g, _)| *g)
            .collect();
        (peaks, samples, flagged)
    }

    /// One lane, two and two with a helper give the same results in the same order: the
    /// drive and model stages run on one lane at a time, their steps and batches in order,
    /// wherever they run. Against the run's peaks (the shared floor, which lets moves go
    /// whole, rises as the lanes get there), the same run peaks, samples and flagged lines.
    #[test]
    fn the_results_do_not_depend_on_the_lanes() {
        let gcode = cube();
        let one = results(&gcode, 1, false);
        assert!(one.len() > 8000, "{} results", one.len());
        let groups: Vec<u64> = one.iter().map(|r| r.0).collect();
        assert!(groups.windows(2).all(|g| g[0] < g[1]), "in file order");
        let one_peaks = peaks(&results(&gcode, 1, true));
        assert_eq!(one_peaks, peaks(&one));
        for threads in [2, 3] {
            assert!(results(&gcode, threads, false) == one, "{threads} threads");
            assert_eq!(peaks(&results(&gcode, threads, true)), one_peaks);
        }
    }

    /// A panic on either lane (the firmware's side, here in the edit of its events, or the
    /// results' side, here in `on_move`) stops the other lanes instead of leaving them
    /// waiting for it for ever: the run ends, and the panic comes out of it.
    #[test]
    fn a_panic_on_a_lane_ends_the_run() {
        let gcode = cube();
        for threads in [1, 2, 3] {
            for in_firmware in [true, false] {
                let gcode = gcode.clone();
                let (done, finished) = mpsc::channel();
                std::thread::spawn(move || {
                    let machine = kossel_machine();
                    let mut events = 0;
                    let mut edit = |e: &Event, to: &mut dyn FnMut(&Event)| {
                        events += 1;
                        assert!(
                            !(in_firmware && events == 3000),
                            "a bug in the firmware lane"
                        );
                        to(e);
                    };
                    let mut moves = 0;
                    let on_move = |_: &mut super::super::MoveResult<()>| {
                        moves += 1;
                        assert!(in_firmware || moves != 3000, "a bug in the model lane");
                    };
                    let run = catch_unwind(AssertUnwindSafe(|| {
                        run_on(
                            &gcode[..],
                            &machine,
                            (),
                            &mut edit,
                            on_move,
                            |_| {},
                            threads,
                        )
                    }));
                    let _ = done.send(run.is_err());
                });
                let panicked = finished
                    .recv_timeout(Duration::from_secs(60))
                    .expect("the run ends");
                assert!(
                    panicked,
                    "{threads} threads, in the firmware lane: {in_firmware}"
                );
            }
        }
    }
}
