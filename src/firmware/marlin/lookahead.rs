//! The block buffer and `Planner::recalculate` (planner.cpp): a ring of
//! `BLOCK_BUFFER_SIZE` slots holding at most B − 1 blocks, the executing one included;
//! after each new block a reverse pass (newest to oldest) and a forward pass set the
//! entry speeds of the blocks not yet frozen. The executing ("busy") block and the entry of
//! the block after it are frozen: the stepper has started them. With the parser never the
//! bottleneck, motion starts when the buffer first fills, and each time a block finishes
//! the next one starts and one more is read (marlin-delta-spec.md §5.4).

use std::collections::VecDeque;

use super::block::Block;

/// Blocks waiting or executing, oldest first.
#[derive(Clone, Debug)]
pub struct Lookahead {
    queue: VecDeque<Block>,
    /// `BLOCK_BUFFER_SIZE − 1`.
    capacity: usize,
    /// The oldest block is executing.
    busy: bool,
    /// `MINIMUM_PLANNER_SPEED²`.
    mps_sqr: f64,
}

/// A block whose plan is final, with its entry and exit speeds, mm/s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planned {
    pub block: Block,
    pub entry_mm_s: f64,
    pub exit_mm_s: f64,
}

impl Lookahead {
    pub fn new(block_buffer_size: usize, minimum_planner_speed_mm_s: f64) -> Lookahead {
        Lookahead {
            queue: VecDeque::with_capacity(block_buffer_size),
            capacity: block_buffer_size.saturating_sub(1).max(1),
            busy: false,
            mps_sqr: minimum_planner_speed_mm_s * minimum_planner_speed_mm_s,
        }
    }

    /// Makes room for one more block: when the buffer is full, the oldest block runs to
    /// its end (it is handed to `out`) and the next one starts. Returns `moves_queued`, the
    /// blocks waiting before the new one.
    pub fn make_room(&mut self, out: &mut impl FnMut(Planned)) -> usize {
        if self.queue.len() >= self.capacity {
            self.busy = true;
            self.pop(out);
        }
        self.queue.len() - usize::from(self.busy)
    }

    /// Adds a block and replans the blocks not frozen.
    pub fn push(&mut self, b: Block) {
        self.queue.push_back(b);
        self.recalculate();
    }

    /// The first block whose entry may still change: after the executing one and the one
    /// whose entry its exit froze; before motion, every block after the first (which starts
    /// from rest).
    fn first_free(&self) -> usize {
        if self.busy { 2 } else { 1 }
    }

    /// The reverse and forward passes (`reverse_pass_kernel`, `forward_pass_kernel`); the
    /// newest block must be able to stop at `MINIMUM_PLANNER_SPEED`.
    fn recalculate(&mut self) {
        let first = self.first_free();
        let q = &mut self.queue;
        let mut next_entry = self.mps_sqr;
        for k in (first..q.len()).rev() {
            let b = &mut q[k];
            b.entry_sqr = b
                .max_entry_sqr
                .min(next_entry + 2.0 * b.accel_mm_s2 * b.millimeters);
            next_entry = b.entry_sqr;
        }
        let (front, back) = q.as_mut_slices();
        let mut prev: Option<&Block> = None;
        for (k, b) in front.iter_mut().chain(back.iter_mut()).enumerate() {
            if k >= first.max(1)
                && let Some(p) = prev
                && p.entry_sqr < b.entry_sqr
            {
                let reach = p.entry_sqr + 2.0 * p.accel_mm_s2 * p.millimeters;
                if reach < b.entry_sqr {
                    b.entry_sqr = reach;
                }
            }
            prev = Some(b);
        }
    }

    fn pop(&mut self, out: &mut impl FnMut(Planned)) {
        if let Some(block) = self.queue.pop_front() {
            let exit_sqr = self.queue.front().map_or(self.mps_sqr, |n| n.entry_sqr);
            out(Planned {
                block,
                entry_mm_s: block.entry_sqr.sqrt(),
                exit_mm_s: exit_sqr.sqrt(),
            });
        }
    }

    /// A synchronising command (G4, M400, G28…) or the end: every block runs, the last
    /// one to `MINIMUM_PLANNER_SPEED`; the buffer is empty and idle after.
    pub fn flush(&mut self, out: &mut impl FnMut(Planned)) {
        while !self.queue.is_empty() {
            self.pop(out);
        }
        self.busy = false;
    }
}
