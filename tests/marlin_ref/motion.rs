//! Marlin's G-code state and motion commands on a delta (spec §3, §8, §9): G0/G1 through
//! `prepare_line_to_destination` (radius clamp, the delta segmenter), G2/G3 through
//! `plan_arc`, `buffer_line` (IK → steps), and the modal state.

use super::kinematics::Delta;
use super::line::Line;
use super::planner::{E, Planner};
use super::{Options, Segmenter};

/// Marlin's arc defaults (`ARC_SUPPORT`): `MIN_ARC_SEGMENT_MM`, `MAX_ARC_SEGMENT_MM`,
/// `MIN_CIRCLE_SEGMENTS`, `N_ARC_CORRECTION`; `ARC_SEGMENTS_PER_SEC` off.
pub const MIN_ARC_SEGMENT_MM: f64 = 0.1;
pub const MAX_ARC_SEGMENT_MM: f64 = 1.0;
pub const MIN_CIRCLE_SEGMENTS: u32 = 72;
pub const N_ARC_CORRECTION: u32 = 25;
/// The UBL segmenter's `SEGMENT_MIN_LENGTH` on a kinematic machine.
pub const UBL_SEGMENT_MIN_LENGTH: f64 = 0.10;
/// `DEFAULT_FEEDRATE_MM_M` when undefined: 4000 mm/min.
pub const DEFAULT_FEEDRATE_MM_S: f64 = 4000.0 / 60.0;

/// `NEAR_ZERO`: |x| < 1e-6.
fn near_zero(x: f64) -> bool {
    x.abs() < 0.000001
}

/// The machine as the G-code sees it.
#[derive(Debug)]
pub struct Printer {
    pub planner: Planner,
    pub delta: Delta,
    pub segmenter: Segmenter,
    pub no_motion_before_homing: bool,
    /// `segments_per_second` (M665 S).
    pub segments_per_second: f64,
    /// `current_position`: native x, y, z, e.
    pub current: [f64; 4],
    /// `position_cart`: the last Cartesian target given to `buffer_line`.
    pub position_cart: [f64; 4],
    /// `position_shift` (G92 X Y Z).
    pub shift: [f64; 3],
    /// `feedrate_mm_s`.
    pub feedrate_mm_s: f64,
    /// `feedrate_percentage` (M220) and its backup.
    pub feedrate_percentage: i32,
    pub backup_feedrate_percentage: i32,
    /// `axis_relative` bits of X, Y, Z, E (G90/G91) …
    pub relative: [bool; 4],
    /// … and the E override of M82/M83 (Some(true): M83).
    pub e_relative_override: Option<bool>,
    /// All axes homed.
    pub homed: bool,
    /// Soft endstops on (M211).
    pub soft_endstops: bool,
    /// Moves refused (NO_MOTION_BEFORE_HOMING, bad arcs) or dropped (unreachable).
    pub refused: usize,
}

impl Printer {
    pub fn new(
        planner: Planner,
        delta: Delta,
        segments_per_second: f64,
        opts: &Options,
    ) -> Printer {
        let home = [0.0, 0.0, delta.home_z, 0.0];
        let mut p = Printer {
            planner,
            delta,
            segmenter: opts.segmenter,
            no_motion_before_homing: opts.no_motion_before_homing,
            segments_per_second,
            current: home,
            position_cart: home,
            shift: [0.0; 3],
            feedrate_mm_s: DEFAULT_FEEDRATE_MM_S,
            feedrate_percentage: 100,
            backup_feedrate_percentage: 100,
            relative: [false; 4],
            e_relative_override: None,
            homed: opts.start_homed,
            soft_endstops: true,
            refused: 0,
        };
        p.sync_towers_to_current();
        p
    }

    /// The planner's tower steps := IK(current) (`sync_plan_position`).
    fn sync_towers_to_current(&mut self) {
        let [x, y, z, _] = self.current;
        let q = self
            .delta
            .carriages(x, y, z)
            .expect("the home position is reachable");
        let spm = self.planner.settings.spm;
        self.planner
            .set_tower_position([0, 1, 2].map(|i| (q[i] * spm[i]).round() as i64));
        self.position_cart = self.current;
    }

    fn axis_is_relative(&self, axis: usize) -> bool {
        if axis == E
            && let Some(rel) = self.e_relative_override
        {
            return rel;
        }
        self.relative[axis]
    }

    /// `MMS_SCALED(feedrate_mm_s)`.
    fn scaled_feedrate(&self) -> f64 {
        self.feedrate_mm_s * 0.01 * self.feedrate_percentage as f64
    }

    /// One command.
    pub fn execute(&mut self, l: &Line) {
        match (l.letter, l.number) {
            (b'G', 0) | (b'G', 1) => self.g0_g1(l),
            (b'G', 2) => self.g2_g3(l, true),
            (b'G', 3) => self.g2_g3(l, false),
            (b'G', 4) => self.g4(l),
            (b'G', 28) => self.g28(),
            (b'G', 90) => {
                self.relative = [false; 4];
                self.e_relative_override = None;
            }
            (b'G', 91) => {
                self.relative = [true; 4];
                self.e_relative_override = None;
            }
            (b'G', 92) => self.g92(l),
            (b'M', 82) => self.e_relative_override = Some(false),
            (b'M', 83) => self.e_relative_override = Some(true),
            (b'M', 201) => {
                for (i, c) in [b'X', b'Y', b'Z', b'E'].into_iter().enumerate() {
                    if let Some(v) = l.val(c) {
                        self.planner.settings.max_accel[i] = v;
                    }
                }
            }
            (b'M', 203) => {
                for (i, c) in [b'X', b'Y', b'Z', b'E'].into_iter().enumerate() {
                    if let Some(v) = l.val(c) {
                        self.planner.settings.max_feedrate[i] = v;
                    }
                }
            }
            (b'M', 204) => {
                let s = &mut self.planner.settings;
                if let Some(v) = l.val(b'S') {
                    s.print_accel = v;
                    s.travel_accel = v;
                }
                if let Some(v) = l.val(b'P') {
                    s.print_accel = v;
                }
                if let Some(v) = l.val(b'R') {
                    s.retract_accel = v;
                }
                if let Some(v) = l.val(b'T') {
                    s.travel_accel = v;
                }
            }
            (b'M', 205) => {
                // B (min segment time) has no effect on a delta (SLOWDOWN compiled out);
                // J is ignored (classic jerk).
                let s = &mut self.planner.settings;
                if let Some(v) = l.val(b'S') {
                    s.min_feedrate = v;
                }
                if let Some(v) = l.val(b'T') {
                    s.min_travel_feedrate = v;
                }
                for (i, c) in [b'X', b'Y', b'Z', b'E'].into_iter().enumerate() {
                    if let Some(v) = l.val(c) {
                        s.jerk[i] = v;
                    }
                }
            }
            (b'M', 211) => {
                if let Some(v) = l.val(b'S') {
                    self.soft_endstops = v != 0.0;
                }
            }
            (b'M', 220) => {
                if !l.any() {
                    return;
                }
                let now = self.feedrate_percentage;
                if l.seen(b'R') {
                    self.feedrate_percentage = self.backup_feedrate_percentage;
                }
                if l.seen(b'B') {
                    self.backup_feedrate_percentage = now;
                }
                if let Some(v) = l.val(b'S') {
                    // value_int(); 0 % or less would stop every move: ignored here.
                    let v = v.trunc() as i32;
                    if v > 0 {
                        self.feedrate_percentage = v;
                    }
                }
            }
            (b'M', 221) => {
                if let Some(v) = l.val(b'S') {
                    self.planner.settings.flow_percent = v.trunc() as i32;
                }
            }
            // M400 waits for the moves; M109/M190 do not, but they wait at least
            // TEMP_RESIDENCY_TIME (10 s) for the heater, far longer than the queue lasts: the
            // queue runs dry and the next move starts from rest. The wait is not counted.
            (b'M', 400) | (b'M', 109) | (b'M', 190) => self.planner.synchronize(),
            (b'M', 665) => self.m665(l),
            _ => {}
        }
    }

    /// `get_destination_from_command()`.
    fn destination(&mut self, l: &Line) -> [f64; 4] {
        let mut dest = self.current;
        for (i, c) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = l.val(c) {
                dest[i] = if self.axis_is_relative(i) {
                    self.current[i] + v
                } else {
                    v - self.shift[i]
                };
            }
        }
        if let Some(v) = l.val(b'E') {
            dest[E] = if self.axis_is_relative(E) {
                self.current[E] + v
            } else {
                v
            };
        }
        if let Some(f) = l.val(b'F')
            && f > 0.0
        {
            self.feedrate_mm_s = f / 60.0;
        }
        dest
    }

    /// `MOTION_CONDITIONS` with NO_MOTION_BEFORE_HOMING.
    fn motion_allowed(&mut self) -> bool {
        if self.no_motion_before_homing && !self.homed {
            self.refused += 1;
            return false;
        }
        true
    }

    fn g0_g1(&mut self, l: &Line) {
        if !self.motion_allowed() {
            return;
        }
        let mut dest = self.destination(l);
        self.prepare_line_to_destination(&mut dest);
    }

    /// `apply_motion_limits`: the radius clamp (which scales Z too) and the Z clamp, when
    /// soft endstops are on and the machine is homed.
    fn apply_motion_limits(&self, t: &mut [f64; 4]) {
        if !self.soft_endstops || !self.homed {
            return;
        }
        let r = self.delta.print_radius;
        let dist_2 = t[0] * t[0] + t[1] * t[1];
        if dist_2 > r * r {
            let k = r / dist_2.sqrt();
            t[0] *= k;
            t[1] *= k;
            t[2] *= k;
        }
        t[2] = t[2].clamp(0.0, self.delta.home_z);
    }

    /// `prepare_line_to_destination()`.
    fn prepare_line_to_destination(&mut self, dest: &mut [f64; 4]) {
        self.apply_motion_limits(dest);
        let moved = match self.segmenter {
            Segmenter::Plain => self.line_to_destination_kinematic(*dest),
            Segmenter::Ubl => self.line_to_destination_segmented(*dest),
        };
        if moved {
            self.current = *dest;
        } else {
            self.refused += 1;
        }
    }

    /// `line_to_destination_kinematic()` (spec §3.2). Returns whether it moved.
    fn line_to_destination_kinematic(&mut self, dest: [f64; 4]) -> bool {
        let fr = self.scaled_feedrate();
        let diff: [f64; 4] = [0, 1, 2, 3].map(|i| dest[i] - self.current[i]);
        if diff[0] == 0.0 && diff[1] == 0.0 {
            self.buffer_line(dest, fr, 0.0, 0.0);
            return true;
        }
        if !self.delta.reachable(dest[0], dest[1]) {
            return false;
        }
        let mut cartesian_mm = (diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2]).sqrt();
        if cartesian_mm < 0.000001 {
            cartesian_mm = diff[E].abs();
        }
        if cartesian_mm < 0.000001 {
            return false;
        }
        let segments = plain_segment_count(cartesian_mm, fr, self.segments_per_second);
        let inv_segments = 1.0 / segments as f64;
        let step = diff.map(|d| d * inv_segments);
        let hint = cartesian_mm * inv_segments;
        let mut raw = self.current;
        for _ in 1..segments {
            for i in 0..4 {
                raw[i] += step[i];
            }
            if !self.buffer_line(raw, fr, hint, 0.0) {
                break;
            }
        }
        self.buffer_line(dest, fr, hint, 0.0);
        true
    }

    /// UBL's `line_to_destination_segmented()` with leveling inactive (spec §3.3).
    fn line_to_destination_segmented(&mut self, dest: [f64; 4]) -> bool {
        if !self.delta.reachable(dest[0], dest[1]) {
            return false;
        }
        let fr = self.scaled_feedrate();
        let total: [f64; 4] = [0, 1, 2, 3].map(|i| dest[i] - self.current[i]);
        let (segments, hint) = ubl_segment_count(total, fr, self.segments_per_second);
        let inv_segments = 1.0 / segments as f64;
        let diff = total.map(|d| d * inv_segments);
        let mut raw = self.current;
        for _ in 1..segments {
            for i in 0..4 {
                raw[i] += diff[i];
            }
            self.buffer_line(raw, fr, hint, 0.0);
        }
        self.buffer_line(dest, fr, hint, 0.0);
        true
    }

    /// `Planner::buffer_line` (kinematic, spec §3.5): IK, steps, `buffer_segment`.
    fn buffer_line(&mut self, cart: [f64; 4], fr: f64, hint_mm: f64, safe_exit_sqr: f64) -> bool {
        let dist = [0, 1, 2].map(|i| cart[i] - self.position_cart[i]);
        let Some(q) = self.delta.carriages(cart[0], cart[1], cart[2]) else {
            // Out of the arms' reach (only unclamped, unhomed moves get here): Marlin's IK
            // would give NaN; the segment is dropped.
            self.refused += 1;
            return false;
        };
        let mm = if hint_mm != 0.0 {
            hint_mm
        } else if dist[0] != 0.0 || dist[1] != 0.0 {
            (dist[0] * dist[0] + dist[1] * dist[1] + dist[2] * dist[2]).sqrt()
        } else {
            dist[2].abs()
        };
        let spm = self.planner.settings.spm;
        // lroundf: round half away from zero.
        let target = [
            (q[0] * spm[0]).round() as i64,
            (q[1] * spm[1]).round() as i64,
            (q[2] * spm[2]).round() as i64,
            (cart[E] * spm[E]).round() as i64,
        ];
        self.planner
            .buffer_segment(target, dist, fr, mm, safe_exit_sqr);
        self.position_cart = cart;
        true
    }

    /// G2/G3 (`GcodeSuite::G2_G3`).
    fn g2_g3(&mut self, l: &Line, clockwise: bool) {
        if !self.motion_allowed() {
            return;
        }
        let dest = self.destination(l);
        let mut offset = [0.0, 0.0];
        if let Some(r) = l.val(b'R') {
            if r != 0.0 {
                let p1 = [self.current[0], self.current[1]];
                let p2 = [dest[0], dest[1]];
                if p1 != p2 {
                    let d2 = [(p2[0] - p1[0]) * 0.5, (p2[1] - p1[1]) * 0.5];
                    let e = if clockwise ^ (r < 0.0) { -1.0 } else { 1.0 };
                    let len = (d2[0] * d2[0] + d2[1] * d2[1]).sqrt();
                    let h2 = (r - len) * (r + len);
                    let h = if h2 >= 0.0 { h2.sqrt() } else { 0.0 };
                    let s = [-d2[1], d2[0]];
                    offset = [d2[0] + s[0] / len * e * h, d2[1] + s[1] / len * e * h];
                }
            }
        } else {
            if let Some(i) = l.val(b'I') {
                offset[0] = i;
            }
            if let Some(j) = l.val(b'J') {
                offset[1] = j;
            }
        }
        if offset[0] != 0.0 || offset[1] != 0.0 {
            self.plan_arc(dest, offset, clockwise, l);
        } else {
            self.refused += 1; // "G2/G3: Bad parameters"
        }
    }

    /// `plan_arc` (spec §8): one `buffer_line` per chord, not split again by the delta
    /// segmenter.
    fn plan_arc(&mut self, cart: [f64; 4], offset: [f64; 2], clockwise: bool, l: &Line) {
        let tau = std::f64::consts::TAU;
        let mut rvec = [-offset[0], -offset[1]];
        let radius = (rvec[0] * rvec[0] + rvec[1] * rvec[1]).sqrt();
        let center = [self.current[0] - rvec[0], self.current[1] - rvec[1]];
        let rt = [cart[0] - center[0], cart[1] - center[1]];
        let start_l = self.current[2];
        let start_e = self.current[E];
        let mut angular_travel;
        let abs_angular_travel;
        let min_segments: u32;
        if near_zero(self.current[0] - cart[0]) && near_zero(self.current[1] - cart[1]) {
            angular_travel = if clockwise { -tau } else { tau };
            abs_angular_travel = tau;
            min_segments = MIN_CIRCLE_SEGMENTS;
        } else {
            angular_travel =
                (rvec[0] * rt[1] - rvec[1] * rt[0]).atan2(rvec[0] * rt[0] + rvec[1] * rt[1]);
            if angular_travel == 0.0 {
                return;
            }
            if angular_travel > 0.0 && clockwise {
                angular_travel -= tau;
            } else if angular_travel < 0.0 && !clockwise {
                angular_travel += tau;
            }
            abs_angular_travel = angular_travel.abs();
            min_segments = (MIN_CIRCLE_SEGMENTS as f64 * (abs_angular_travel / tau)).ceil() as u32;
        }
        let travel_l = cart[2] - start_l;
        let travel_e = cart[E] - start_e;
        let flat_mm = radius * abs_angular_travel;
        if flat_mm < 0.0001 && near_zero(travel_l) {
            if !near_zero(travel_e) {
                self.g0_g1(l); // retract/recover as G1
            }
            return;
        }
        let fr = self.scaled_feedrate();
        let segments = arc_segment_count(flat_mm, min_segments);
        let segment_mm = flat_mm / segments as f64;
        let settings = &self.planner.settings;
        let limiting_accel = settings.max_accel[0].min(settings.max_accel[1]);
        let limiting_speed = settings.max_feedrate[0].min(settings.max_feedrate[1]);
        let limiting_speed_sqr = (limiting_speed * limiting_speed)
            .min(limiting_accel * radius)
            .min(fr * fr);
        if segments > 1 {
            let theta_per_segment = angular_travel / segments as f64;
            let sq_theta = theta_per_segment * theta_per_segment;
            let sin_t = theta_per_segment - sq_theta * theta_per_segment / 6.0;
            let cos_t = 1.0 - 0.5 * sq_theta;
            let per_segment_l = travel_l / segments as f64;
            let per_segment_e = travel_e / segments as f64;
            let mut arc_recalc_count = N_ARC_CORRECTION;
            for i in 1..segments {
                arc_recalc_count -= 1;
                if arc_recalc_count != 0 {
                    let r_new_y = rvec[0] * sin_t + rvec[1] * cos_t;
                    rvec[0] = rvec[0] * cos_t - rvec[1] * sin_t;
                    rvec[1] = r_new_y;
                } else {
                    arc_recalc_count = N_ARC_CORRECTION;
                    let ti = i as f64 * theta_per_segment;
                    let (sin_ti, cos_ti) = ti.sin_cos();
                    rvec[0] = -offset[0] * cos_ti + offset[1] * sin_ti;
                    rvec[1] = -offset[0] * sin_ti - offset[1] * cos_ti;
                }
                let mut raw = [
                    center[0] + rvec[0],
                    center[1] + rvec[1],
                    start_l + per_segment_l * i as f64,
                    start_e + per_segment_e * i as f64,
                ];
                self.apply_motion_limits(&mut raw);
                let arc_mm_remaining = flat_mm - segment_mm * i as f64;
                let safe_exit_sqr = limiting_speed_sqr.min(2.0 * limiting_accel * arc_mm_remaining);
                if !self.buffer_line(raw, fr, 0.0, safe_exit_sqr) {
                    break;
                }
            }
        }
        let mut raw = cart;
        self.apply_motion_limits(&mut raw);
        self.buffer_line(raw, fr, 0.0, 0.0);
        self.current = cart;
    }

    /// G4: synchronize, then dwell (S wins over P).
    fn g4(&mut self, l: &Line) {
        let mut dwell_ms: u64 = 0;
        if let Some(p) = l.val(b'P') {
            dwell_ms = p.max(0.0).trunc() as u64;
        }
        if let Some(s) = l.val(b'S') {
            dwell_ms = (s * 1000.0).max(0.0).trunc() as u64;
        }
        self.planner.synchronize();
        self.planner.dwell(dwell_ms as f64 * 1e-3);
    }

    /// G28: synchronize; the nozzle is declared at (0, 0, home z), the carriages at its IK.
    /// The homing moves themselves are not modelled.
    fn g28(&mut self) {
        self.planner.synchronize();
        self.current[0] = 0.0;
        self.current[1] = 0.0;
        self.current[2] = self.delta.home_z;
        self.shift = [0.0; 3];
        self.homed = true;
        self.sync_towers_to_current();
    }

    /// G92: X/Y/Z shift the workspace; E sets the position (a sync block if moves are queued).
    fn g92(&mut self, l: &Line) {
        if l.sub.unwrap_or(0) != 0 {
            return;
        }
        for (i, c) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = l.val(c) {
                let native = v - self.shift[i];
                let d = native - self.current[i];
                if !near_zero(d) {
                    self.shift[i] += d;
                }
            }
        }
        if let Some(v) = l.val(b'E')
            && !near_zero(v - self.current[E])
        {
            self.current[E] = v;
            self.position_cart[E] = v;
            self.planner.set_e_position(v);
        }
    }

    /// M665 with any parameter: new geometry, then `recalc_delta_settings`, which un-homes.
    fn m665(&mut self, l: &Line) {
        if !l.any() {
            return;
        }
        let d = &mut self.delta;
        if let Some(v) = l.val(b'H') {
            // delta_height: the home z of the next G28 (no probe offset known here).
            d.home_z = v;
        }
        if let Some(v) = l.val(b'L') {
            d.rod = v;
        }
        if let Some(v) = l.val(b'R') {
            d.radius = v;
        }
        if let Some(v) = l.val(b'S') {
            self.segments_per_second = v;
        }
        for (i, c) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = l.val(c) {
                d.angle_trim_deg[i] = v;
            }
        }
        for (i, c) in [b'A', b'B', b'C'].into_iter().enumerate() {
            if let Some(v) = l.val(c) {
                d.rod_trim[i] = v;
            }
        }
        d.recalc();
        self.homed = false;
    }
}

/// `uint16_t segments = segments_per_second · seconds` (a float stored into uint16 on
/// ARM: saturated to uint32, then its low 16 bits), at least 1.
pub fn plain_segment_count(cartesian_mm: f64, fr_mm_s: f64, segments_per_second: f64) -> u32 {
    let seconds = cartesian_mm / fr_mm_s;
    let wide = super::planner::to_u32(segments_per_second * seconds);
    (wide & 0xFFFF).max(1)
}

/// UBL on a delta: min(lround(S · xy / F), lround(xy / 0.1)), at least 1; the hint is the
/// XYZ length over the count.
pub fn ubl_segment_count(total: [f64; 4], fr_mm_s: f64, segments_per_second: f64) -> (u32, f64) {
    let cart_xy_mm_2 = total[0] * total[0] + total[1] * total[1];
    let cart_xy_mm = cart_xy_mm_2.sqrt();
    let seconds = cart_xy_mm / fr_mm_s;
    let lround16 = |v: f64| super::planner::to_u32(v.round()) & 0xFFFF;
    let segments = lround16(segments_per_second * seconds)
        .min(lround16(cart_xy_mm * (1.0 / UBL_SEGMENT_MIN_LENGTH)))
        .max(1);
    let hint = (cart_xy_mm_2 + total[2] * total[2]).sqrt() / segments as f64;
    (segments, hint)
}

/// `plan_arc`'s chord count for an arc of `flat_mm` (spec §8).
pub fn arc_segment_count(flat_mm: f64, min_segments: u32) -> u32 {
    let ideal_segment_mm = MAX_ARC_SEGMENT_MM;
    let nominal_segments = (flat_mm / ideal_segment_mm)
        .floor()
        .max(min_segments as f64);
    let nominal_segment_mm = flat_mm / nominal_segments;
    if nominal_segment_mm > MAX_ARC_SEGMENT_MM {
        (flat_mm / MAX_ARC_SEGMENT_MM).ceil() as u32
    } else if nominal_segment_mm < MIN_ARC_SEGMENT_MM {
        ((flat_mm / MIN_ARC_SEGMENT_MM).floor() as u32).max(1)
    } else {
        nominal_segments as u32
    }
}
