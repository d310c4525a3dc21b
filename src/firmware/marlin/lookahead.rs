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
    ///
    /// A block's reverse entry depends only on the blocks after it, so where the reverse
    /// pass gives a block the value it gave it last time, the blocks before it keep theirs
    /// and their final entries: the passes stop there and the forward pass starts after it
    /// (as Marlin's `block_buffer_planned` spares it replanning what cannot change). The
    /// entries are those of full passes, bit for bit.
    fn recalculate(&mut self) {
        let first = self.first_free();
        let q = &mut self.queue;
        let mut next_entry = self.mps_sqr;
        // The first block whose entry this call sets again.
        let mut from = first;
        for k in (first..q.len()).rev() {
            let b = &mut q[k];
            let reverse = b
                .max_entry_sqr
                .min(next_entry + 2.0 * b.accel_mm_s2 * b.millimeters);
            if reverse.to_bits() == b.reverse_sqr.to_bits() {
                from = k + 1;
                break;
            }
            (b.reverse_sqr, b.entry_sqr) = (reverse, reverse);
            next_entry = reverse;
        }
        let start = from.max(first.max(1));
        // The previous block's entry and the entry it can reach at its end.
        let reach = |b: &Block| {
            (
                b.entry_sqr,
                b.entry_sqr + 2.0 * b.accel_mm_s2 * b.millimeters,
            )
        };
        let mut prev = q.get(start.wrapping_sub(1)).map(reach);
        for b in q.range_mut(start.min(q.len())..) {
            if let Some((entry, reach)) = prev
                && entry < b.entry_sqr
                && reach < b.entry_sqr
            {
                b.entry_sqr = reach;
            }
            prev = Some(reach(b));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The passes over every block not frozen (the plain form of `recalculate`).
    fn full_passes(q: &mut VecDeque<Block>, first: usize, mps_sqr: f64) {
        let mut next = mps_sqr;
        for k in (first..q.len()).rev() {
            let b = &mut q[k];
            b.entry_sqr = b
                .max_entry_sqr
                .min(next + 2.0 * b.accel_mm_s2 * b.millimeters);
            next = b.entry_sqr;
        }
        for k in first.max(1)..q.len() {
            let (p, b) = (q[k - 1], q[k]);
            let reach = p.entry_sqr + 2.0 * p.accel_mm_s2 * p.millimeters;
            if p.entry_sqr < b.entry_sqr && reach < b.entry_sqr {
                q[k].entry_sqr = reach;
            }
        }
    }

    #[test]
    fn stopping_where_nothing_changes_gives_the_full_passes_bit_for_bit() {
        let (mut seed, mut rand) = (7u64, 0.0);
        let mut next = |lo: f64, hi: f64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            rand = (seed >> 11) as f64 / (1u64 << 53) as f64;
            lo + (hi - lo) * rand
        };
        let mut la = Lookahead::new(16, 0.05);
        for k in 0..20_000u64 {
            la.make_room(&mut |_| {});
            // Runs of equal blocks (a segmented line) and changes of speed and length.
            let (mm, speed) = if k % 50 < 40 {
                (0.5, 80.0)
            } else {
                (next(0.01, 5.0), next(1.0, 120.0))
            };
            let block = Block {
                line: k,
                from_steps: [0; 4],
                to_steps: [0; 4],
                step_events: 1,
                millimeters: mm,
                nominal_speed: speed,
                nominal_rate: 1.0,
                accel_steps_s2: 1.0,
                accel_mm_s2: next(500.0, 3000.0),
                max_entry_sqr: speed * speed * next(0.0, 1.0),
                entry_sqr: 0.0025,
                reverse_sqr: f64::NAN,
            };
            let mut full = la.queue.clone();
            full.push_back(block);
            full_passes(&mut full, la.first_free(), la.mps_sqr);
            la.push(block);
            let entries =
                |q: &VecDeque<Block>| q.iter().map(|b| b.entry_sqr.to_bits()).collect::<Vec<_>>();
            assert_eq!(entries(&la.queue), entries(&full), "block {k}");
        }
        assert!(la.busy);
    }
}
