//! The model stage's threads: the lane checking a batch, the other lane when it is free
//! (`lanes`, [`Crew::claim`]) and, on more than two cores, a few helpers share each batch's
//! chunks, claimed one at a time; the helpers sleep between batches.
//!
//! Not rayon's pool: its idle workers wait for work by yielding the processor in a loop
//! (`sched_yield`, 32 rounds before they sleep), and on a machine whose cores the
//! sequential stages keep busy every round is a context switch: two thirds of a shaped
//! run's 49 k switches on the corpus's bunny (docs/performance.md, "Tenth session").

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, PoisonError, RwLock};

/// A job of `parts` parts, done by whoever of the crew is free, each part once.
pub struct Crew<J> {
    /// The job in hand: held for reading while parts of it are done, taken back under the
    /// write lock, which waits for the parts in progress.
    job: RwLock<Option<J>>,
    /// The next part to claim, and the job's number of parts: claimed under the job's read
    /// lock, set under its write lock.
    next: AtomicUsize,
    parts: AtomicUsize,
    /// Jobs handed out so far, and whether the crew is dismissed.
    bell: Mutex<(u64, bool)>,
    rung: Condvar,
}

impl<J: Sync> Crew<J> {
    pub fn new() -> Crew<J> {
        Crew {
            job: RwLock::new(None),
            next: AtomicUsize::new(0),
            parts: AtomicUsize::new(0),
            bell: Mutex::new((0, false)),
            rung: Condvar::new(),
        }
    }

    /// Does the parts `0..parts` of `job`, `work(&job, part)` once each, on this thread
    /// and, if `help`, the helpers ([`Self::help`]) that are free, and gives the job back
    /// when every part is done. `posted` is called once the job can be claimed
    /// ([`Self::claim`]) from other threads.
    pub fn run(
        &self,
        job: J,
        parts: usize,
        help: bool,
        work: &impl Fn(&J, usize),
        posted: impl FnOnce(),
    ) -> J {
        {
            let mut slot = self.job.write().unwrap_or_else(PoisonError::into_inner);
            *slot = Some(job);
            self.next.store(0, Ordering::Relaxed);
            self.parts.store(parts, Ordering::Relaxed);
        }
        if help {
            self.bell.lock().unwrap_or_else(PoisonError::into_inner).0 += 1;
            self.rung.notify_all();
        }
        posted();
        self.claim(work);
        let mut slot = self.job.write().unwrap_or_else(PoisonError::into_inner);
        slot.take()
            .expect("the job stays in the crew until `run` takes it back")
    }

    /// A helper's life: the parts of each job it sees, until [`Self::dismiss`].
    pub fn help(&self, work: &impl Fn(&J, usize)) {
        let mut seen = 0;
        loop {
            {
                let mut bell = self.bell.lock().unwrap_or_else(PoisonError::into_inner);
                while bell.0 == seen && !bell.1 {
                    bell = self.rung.wait(bell).unwrap_or_else(PoisonError::into_inner);
                }
                if bell.1 {
                    return;
                }
                seen = bell.0;
            }
            self.claim(work);
        }
    }

    /// Ends the helpers' lives once they finish what they are doing.
    pub fn dismiss(&self) {
        self.bell.lock().unwrap_or_else(PoisonError::into_inner).1 = true;
        self.rung.notify_all();
    }

    /// Does parts of the job in hand, if any, until none is left to claim; whether it did
    /// any.
    pub fn claim(&self, work: &impl Fn(&J, usize)) -> bool {
        // Without the lock when every part is taken: the lanes ask whenever they are free.
        if self.next.load(Ordering::Relaxed) >= self.parts.load(Ordering::Relaxed) {
            return false;
        }
        let slot = self.job.read().unwrap_or_else(PoisonError::into_inner);
        let mut did = false;
        if let Some(job) = slot.as_ref() {
            let parts = self.parts.load(Ordering::Relaxed);
            loop {
                let part = self.next.fetch_add(1, Ordering::Relaxed);
                if part >= parts {
                    break;
                }
                work(job, part);
                did = true;
            }
        }
        did
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicBool;
    use std::time::{Duration, Instant};

    /// A job: a count per part, whether a helper did a part, and whether one is called.
    struct Tally {
        done: Vec<AtomicUsize>,
        helped: AtomicBool,
        runner: std::thread::ThreadId,
        help: bool,
    }

    /// Every part of every job is done once, the helpers do some of them when called (the
    /// first part of each such job of several parts waits for one), each job comes back,
    /// and the helpers go when dismissed.
    ///
    /// A helper may also take parts of a job it was not called for, or the one part of a
    /// job before its runner does: one still on its way from an earlier call, or woken the
    /// moment the job was posted. Asserting that none did failed under load (and, before
    /// the dismissal on unwinding, hung the test run: the helpers waited for ever).
    #[test]
    fn each_part_is_done_once_and_the_helpers_help() {
        let crew = Crew::<Tally>::new();
        let work = |job: &Tally, part: usize| {
            let mine = std::thread::current().id() == job.runner;
            if !mine {
                job.helped.store(true, Ordering::SeqCst);
            }
            if part == 0 && mine && job.help && job.done.len() > 1 {
                let start = Instant::now();
                while !job.helped.load(Ordering::SeqCst)
                    && start.elapsed() < Duration::from_secs(10)
                {
                    std::thread::yield_now();
                }
            }
            job.done[part].fetch_add(1, Ordering::SeqCst);
        };
        /// Dismisses the helpers however the scope ends: a failed assertion then fails the
        /// test, and the scope does not wait for helpers that wait for a job.
        struct Dismiss<'a>(&'a Crew<Tally>);
        impl Drop for Dismiss<'_> {
            fn drop(&mut self) {
                self.0.dismiss();
            }
        }
        std::thread::scope(|scope| {
            let _dismiss = Dismiss(&crew);
            for _ in 0..3 {
                scope.spawn(|| crew.help(&work));
            }
            for (parts, help) in [(0, true), (1, true), (7, true), (64, false), (500, true)] {
                let job = Tally {
                    done: (0..parts).map(|_| AtomicUsize::new(0)).collect(),
                    helped: AtomicBool::new(false),
                    runner: std::thread::current().id(),
                    help,
                };
                let job = crew.run(job, parts, help, &work, || {});
                for (i, d) in job.done.iter().enumerate() {
                    assert_eq!(d.load(Ordering::SeqCst), 1, "part {i} of {parts}");
                }
                if help && parts > 1 {
                    assert!(job.helped.into_inner(), "{parts} parts");
                }
            }
        });
    }
}
