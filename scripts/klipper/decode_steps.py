#!/usr/bin/env python3
"""Decode Klipper batch-mode step commands into linear-delta carriage heights.

Input: the text that Klipper's klippy/parsedump.py prints for a batch run's
output file (one MCU command per line), the printer.cfg of the run and the
MCU data dictionary (for CLOCK_FREQ).

Model of the MCU (src/stepper.c):
  * reset_step_clock oid clock   -> the stepper's last step time := clock
                                    (32-bit; extended to 64 bits at the next
                                    queue_step, see decode())
  * set_next_step_dir oid dir    -> direction (MCU pin level) used by the
                                    following queue_step commands of that oid
  * queue_step oid interval count add -> `count` steps; step k (k = 0..count-1)
        at  last + (k+1)*interval + add*k*(k+1)/2 ; last := time of final step
  All intervals are relative, so clocks are accumulated as unbounded ints.
  (Batch runs here contain no reset_step_clock: the one at MCU configuration
  is an on-restart command and the one after homing is only sent with a real
  MCU.)
  Logical direction = pin level XOR dir_pin inversion ('!'); logical +1 is an
  increasing stepper position = increasing carriage height (tower coordinate).

Homing: for each stepper the final homing move starts at the clock of the last
`endstop_home ... clock=C` with C != 0 (C = 0 disarms); in batch mode the
endstop "triggers" at the end of the move, so the final homing move runs its
whole length, 2 * homing_retract_dist along the tower (the toolhead is at
x = y = 0), i.e. HOME_STEPS = round(2*retract/step_dist) steps, all +1.
The carriage height at the end of that move is the homed height
    H = position_endstop + sqrt(arm_length^2 - delta_radius^2)
(Klipper's abs_endstops), and afterwards
    q(t) = H + (n(t) - n_home) * step_dist ,
n = running signed step count.

With --no-homing (runs where G28 was replaced by SET_KINEMATIC_POSITION X=0
Y=0 Z=position_endstop before any step), n_home = 0.

Time origin (t_s = 0): the MCU clock of the first carriage step (any of the
three towers) after the end of the last homing (or the first carriage step
of the run with --no-homing).  Seconds = ticks / CLOCK_FREQ.
"""
import argparse, bisect, configparser, gzip, json, math, os, re, sys

import numpy as np

LINE_RE = re.compile(r'^(\w+)((?: \w+=\S+)*)\s*$')


def read_cfg(path):
    cp = configparser.RawConfigParser(inline_comment_prefixes=('#', ';'),
                                      strict=False)
    # Klipper configs have indented continuation lines for macros; configparser
    # handles them as multi-line values.
    with open(path) as f:
        cp.read_file(f)
    return cp


def stepper_params(cp, name, fallback=None):
    sec = cp[name]
    def get(key, default=None):
        if key in sec:
            return sec[key]
        if fallback is not None and key in cp[fallback]:
            return cp[fallback][key]
        return default
    rot = float(get('rotation_distance'))
    micro = int(get('microsteps'))
    full = int(get('full_steps_per_rotation', '200'))
    gear = get('gear_ratio')
    if gear:
        raise SystemExit('gear_ratio not supported by this tool')
    dir_pin = get('dir_pin').strip()
    step_pin = get('step_pin').strip()
    return {
        'step_pin': step_pin.lstrip('!^~'),
        'dir_invert': dir_pin.startswith('!'),
        'step_dist': rot / (micro * full),
    }


def parse_dump(path):
    """Yield (cmd, {param: int_or_str}) for each line of parsedump output."""
    with open(path) as f:
        for line in f:
            m = LINE_RE.match(line)
            if not m:
                continue
            params = {}
            for tok in m.group(2).split():
                k, v = tok.split('=', 1)
                try:
                    params[k] = int(v)
                except ValueError:
                    params[k] = v
            yield m.group(1), params


def decode(dump_path, pin_to_name):
    oid_name = {}
    state = {}      # oid -> [last_clock, dir_bit]
    steps = {}      # oid -> (list of clocks, list of dir bits)
    endstop_starts = []   # clocks of armed endstop_home commands
    for cmd, p in parse_dump(dump_path):
        if cmd == 'queue_step':
            oid = p['oid']
            st = state[oid]
            interval, count, add = p['interval'], p['count'], p['add']
            clk = st[0]
            if st[2] is not None:
                # after reset_step_clock the MCU's time base is the 32-bit
                # clock given; the first step is the first clock at/after the
                # previous step with the MCU's low 32 bits
                low = (st[2] + interval) & 0xffffffff
                clk = clk + ((low - clk) & 0xffffffff) - interval
                st[2] = None
            clocks, dirs = steps[oid]
            d = st[1]
            for k in range(count):
                clk += interval + add * k
                clocks.append(clk)
            dirs.append((len(clocks) - count, count, d))
            st[0] = clk
        elif cmd == 'set_next_step_dir':
            state[p['oid']][1] = p['dir']
        elif cmd == 'reset_step_clock':
            state[p['oid']][2] = p['clock']
        elif cmd == 'config_stepper':
            oid = p['oid']
            oid_name[oid] = pin_to_name.get(p['step_pin'], 'oid%d' % oid)
            state[oid] = [0, 0, None]   # last step clock, dir, pending reset
            steps[oid] = ([], [])
        elif cmd == 'endstop_home':
            if p['clock'] != 0:
                endstop_starts.append(p['clock'])
    return oid_name, steps, endstop_starts


def to_arrays(clock_list, dir_runs, invert):
    clocks = np.asarray(clock_list, dtype=np.int64)
    sgn = np.empty(len(clocks), dtype=np.int64)
    for start, count, d in dir_runs:
        sgn[start:start + count] = 1 if (d ^ invert) else -1
    return clocks, sgn


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--cfg', required=True)
    ap.add_argument('--dict', required=True, help='MCU data dictionary (JSON)')
    ap.add_argument('--dump', required=True, help='parsedump.py text output')
    ap.add_argument('--out', required=True, help='output prefix (path/name)')
    ap.add_argument('--grid-ms', type=float, default=1.0)
    ap.add_argument('--decimate-ms', type=float, default=2.0,
                    help='also write PREFIX_2ms.csv at this spacing (0 = no)')
    ap.add_argument('--full', action='store_true',
                    help='also write the full-resolution step timeline '
                         '(PREFIX_steps.csv.gz and PREFIX_steps.npz)')
    ap.add_argument('--no-homing', action='store_true',
                    help='the run has no G28 but SET_KINEMATIC_POSITION at the '
                         'home position before any step: count 0 = homed')
    ap.add_argument('--end-only', action='store_true',
                    help='only compute the summary (no CSV)')
    args = ap.parse_args()

    with open(args.dict) as f:
        freq = int(json.load(f)['config']['CLOCK_FREQ'])
    cp = read_cfg(args.cfg)
    names = ['stepper_a', 'stepper_b', 'stepper_c']
    sp = {n: stepper_params(cp, n, fallback='stepper_a') for n in names}
    pin_to_name = {v['step_pin']: n for n, v in sp.items()}
    if 'extruder' in cp:
        pin_to_name[cp['extruder']['step_pin'].strip().lstrip('!^~')] = 'extruder'
    radius = float(cp['printer']['delta_radius'])
    arm_a = float(cp['stepper_a']['arm_length'])
    pe_a = float(cp['stepper_a']['position_endstop'])
    retract = float(cp['stepper_a'].get('homing_retract_dist', '5'))
    homed = {}
    for n in names:
        arm = float(cp[n].get('arm_length', arm_a))
        pe = float(cp[n].get('position_endstop', pe_a))
        homed[n] = pe + math.sqrt(arm ** 2 - radius ** 2)

    oid_name, steps, endstop_starts = decode(args.dump, pin_to_name)
    name_oid = {v: k for k, v in oid_name.items()}
    if not endstop_starts and not args.no_homing:
        raise SystemExit('no homing (endstop_home) found in the dump '
                         '(use --no-homing for SET_KINEMATIC_POSITION runs)')
    home_start = max(endstop_starts) if endstop_starts else None

    per = {}
    for n in names:
        oid = name_oid[n]
        clocks, sgn = to_arrays(steps[oid][0], steps[oid][1],
                                int(sp[n]['dir_invert']))
        cum = np.cumsum(sgn)
        sd = sp[n]['step_dist']
        if args.no_homing:
            # SET_KINEMATIC_POSITION X=0 Y=0 Z=<position_endstop> before any
            # step: the count 0 is the homed height
            if endstop_starts:
                raise SystemExit('--no-homing but the dump has homing moves')
            per[n] = dict(oid=oid, clocks=clocks, sgn=sgn, cum=cum, sd=sd,
                          n_home=0, home_end_clock=None, first_after=0,
                          H=homed[n])
            continue
        home_steps = int(round(2 * retract / sd))
        i0 = int(np.searchsorted(clocks, home_start, side='left'))
        ih = i0 + home_steps - 1          # index of last homing step
        if ih >= len(clocks) or not np.all(sgn[i0:ih + 1] == 1):
            raise SystemExit('%s: final homing move not found as %d +steps'
                             % (n, home_steps))
        per[n] = dict(oid=oid, clocks=clocks, sgn=sgn, cum=cum, sd=sd,
                      n_home=int(cum[ih]), home_end_clock=int(clocks[ih]),
                      first_after=int(ih + 1), H=homed[n])
    firsts = [int(p['clocks'][p['first_after']]) for p in per.values()
              if p['first_after'] < len(p['clocks'])]
    if args.no_homing:
        home_end = None
    else:
        home_end = max(p['home_end_clock'] for p in per.values())
        # sanity: no stepper steps between its own homing end and home_end
        for n, p in per.items():
            j = p['first_after']
            if j < len(p['clocks']) and p['clocks'][j] <= home_end:
                raise SystemExit('%s steps before all towers finished homing'
                                 % n)
    origin = min(firsts)
    last = max(int(p['clocks'][-1]) for p in per.values())
    ext_last = None
    if 'extruder' in name_oid and steps[name_oid['extruder']][0]:
        ext_last = int(steps[name_oid['extruder']][0][-1])

    def pos_at(p, c):
        """carriage height (mm) in force at clock array c (step at c counts)."""
        idx = np.searchsorted(p['clocks'], c, side='right') - 1
        n = np.where(idx >= 0, p['cum'][np.maximum(idx, 0)], 0)
        return p['H'] + (n - p['n_home']) * p['sd']

    summary = {
        'clock_freq_hz': freq,
        'step_dist_mm': {n: per[n]['sd'] for n in names},
        'oids': {n: per[n]['oid'] for n in names},
        'homed_height_mm': {n: per[n]['H'] for n in names},
        'homed_step_count': {n: per[n]['n_home'] for n in names},
        'final_homing_move_start_clock': home_start,
        'homing_end_clock': home_end,
        'origin_clock': origin,
        'origin_s_abs': origin / freq,
        'homing_end_s_rel': None if home_end is None
        else (home_end - origin) / freq,
        'last_carriage_step_clock': last,
        'end_time_s': (last - origin) / freq,
        'end_time_ticks': last - origin,
        'last_extruder_step_s_rel': None if ext_last is None
        else (ext_last - origin) / freq,
        'steps_after_homing': {n: int(len(per[n]['clocks']) - per[n]['first_after'])
                               for n in names},
        'final_height_mm': {n: float(pos_at(per[n], np.array([last]))[0])
                            for n in names},
    }
    with open(args.out + '_summary.json', 'w') as f:
        json.dump(summary, f, indent=1)
    json.dump(summary, sys.stdout, indent=1)
    sys.stdout.write('\n')
    if args.end_only:
        return

    def write_grid(path, spacing_ms, fmt_q):
        ticks = int(round(spacing_ms * 1e-3 * freq))
        if abs(ticks - spacing_ms * 1e-3 * freq) > 1e-6:
            raise SystemExit('grid spacing not a whole number of ticks')
        k = np.arange(0, (last - origin) // ticks + 1, dtype=np.int64)
        c = origin + k * ticks
        if c[-1] != last:
            c = np.append(c, last)
        qs = [pos_at(per[n], c) for n in names]
        t = (c - origin) / freq
        tdec = max(0, -int(math.floor(math.log10(spacing_ms * 1e-3) + 1e-9)))
        with open(path, 'w') as f:
            f.write('t_s,q1_mm,q2_mm,q3_mm\n')
            for i in range(len(c)):
                if i == len(c) - 1 and (c[i] - origin) % ticks:
                    ts = repr(float(t[i]))     # exact end time (off grid)
                else:
                    ts = '%.*f' % (tdec, t[i])
                f.write('%s,%s,%s,%s\n' % (ts, fmt_q % qs[0][i],
                                           fmt_q % qs[1][i], fmt_q % qs[2][i]))

    write_grid(args.out + '_1ms.csv', args.grid_ms, '%.7f')
    if args.decimate_ms:
        write_grid(args.out + '_2ms.csv', args.decimate_ms, '%.4f')
    if args.full:
        # merged step timeline after homing: one row per step event
        allc = np.unique(np.concatenate(
            [per[n]['clocks'][per[n]['first_after']:] for n in names]))
        qs = [pos_at(per[n], allc) for n in names]
        with gzip.open(args.out + '_steps.csv.gz', 'wt') as f:
            f.write('t_s,q1_mm,q2_mm,q3_mm\n')
            # heights at t=origin- (homed) first
            if home_end is not None:
                f.write('%r,%.7f,%.7f,%.7f\n' % (
                    (home_end - origin) / freq, per['stepper_a']['H'],
                    per['stepper_b']['H'], per['stepper_c']['H']))
            for i in range(len(allc)):
                f.write('%.10f,%.7f,%.7f,%.7f\n' % (
                    (allc[i] - origin) / freq, qs[0][i], qs[1][i], qs[2][i]))
        np.savez_compressed(
            args.out + '_steps.npz', freq=freq, origin=origin,
            **{'%s_clock' % n: per[n]['clocks'][per[n]['first_after']:] - origin
               for n in names},
            **{'%s_pos_mm' % n: per[n]['H'] + (per[n]['cum'][per[n]['first_after']:]
                                               - per[n]['n_home']) * per[n]['sd']
               for n in names})


if __name__ == '__main__':
    main()
