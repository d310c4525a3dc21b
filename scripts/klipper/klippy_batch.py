#!/usr/bin/env python3
"""Run klippy unchanged, but log every toolhead trapq move (and set_position).

Usage: [KLIPPY_MOVELOG=moves.csv] [KLIPPY_BATCH_HOMING_FIX=1] \
       python klippy_batch.py KLIPPER_DIR <klippy.py args...>

KLIPPY_BATCH_HOMING_FIX=1 (used for the input-shaper runs only): at the start
of each homing move, after flushing step generation, set each stepper's
host-side MCU position to the step count actually emitted (the stepcompress
position).  On a real printer Klipper does this itself by querying the MCU
(stepper._query_mcu_position at connect and after every homing move); in batch
mode those queries are skipped, and with [input_shaper] on a delta the host
position is then off by round(sqrt(arm^2-radius^2)/step_dist) steps (the input
shaper swaps in its stepper kinematics, whose commanded position is still 0,
in set_stepper_kinematics), so batch-mode G28 "over-steps" and leaves the
toolhead at z = 477.6125 instead of 290.  Without [input_shaper] the fix
changes nothing (checked: identical step streams).

Only observes: wraps ToolHead.trapq_append (the C function that receives the
planned trapezoids) and ToolHead.set_position with functions that write one
CSV line and then call the original.  The MCU output must be byte-identical
to a plain klippy.py run (checked in the README).

CSV columns (one row per trapq_append on the toolhead's trapq):
  kind=M, print_time, accel_t, cruise_t, decel_t, start_x, start_y, start_z,
  axes_r_x, axes_r_y, axes_r_z, start_v, cruise_v, accel
kind=E rows: the same for the extruder's own trapq (start_x = E position,
axes_r_x = E ratio; E-only moves appear only here), and kind=P rows for
set_position: print_time, x, y, z, homing_axes.
"""
import os, sys

kdir = os.path.join(os.path.abspath(sys.argv[1]), 'klippy')
sys.path.insert(0, kdir)
out = open(os.environ.get('KLIPPY_MOVELOG', os.devnull), 'w')
out.write('kind,print_time,accel_t,cruise_t,decel_t,start_x,start_y,start_z,'
          'axes_r_x,axes_r_y,axes_r_z,start_v,cruise_v,accel\n')

import toolhead  # noqa: E402  (same module object klippy.py imports)

_orig_init = toolhead.ToolHead.__init__
_orig_setpos = toolhead.ToolHead.set_position


def _init(self, config):
    _orig_init(self, config)
    real = self.trapq_append
    mytrapq = self.trapq

    def logged(tq, *a):
        if tq is mytrapq:
            out.write('M,' + ','.join(repr(float(v)) for v in a) + '\n')
        return real(tq, *a)
    self.trapq_append = logged


def _setpos(self, newpos, homing_axes=""):
    r = _orig_setpos(self, newpos, homing_axes)
    out.write('P,%r,%r,%r,%r,%s\n' % (self.print_time, float(newpos[0]),
                                      float(newpos[1]), float(newpos[2]),
                                      homing_axes or '-'))
    return r


import kinematics.extruder as kext  # noqa: E402
_orig_einit = kext.PrinterExtruder.__init__


def _einit(self, config, *a, **kw):
    _orig_einit(self, config, *a, **kw)
    real = self.trapq_append

    def logged(tq, *a):
        out.write('E,' + ','.join(repr(float(v)) for v in a) + '\n')
        return real(tq, *a)
    self.trapq_append = logged


kext.PrinterExtruder.__init__ = _einit
toolhead.ToolHead.__init__ = _init

if os.environ.get('KLIPPY_BATCH_HOMING_FIX') == '1':
    import chelper  # noqa: E402
    import extras.homing as homing  # noqa: E402
    _orig_homing_move = homing.HomingMove.homing_move

    def _homing_move(self, *a, **kw):
        self.toolhead.flush_step_generation()
        ffi_main, ffi_lib = chelper.get_ffi()
        for s in self.toolhead.get_kinematics().get_steppers():
            pos = ffi_lib.stepcompress_find_past_position(s._stepqueue,
                                                          (1 << 63) - 1)
            if pos != s.get_mcu_position():
                sys.stderr.write('homing fix: %s host mcu position %d -> %d\n'
                                 % (s.get_name(), s.get_mcu_position(), pos))
            s._set_mcu_position(int(pos))
        return _orig_homing_move(self, *a, **kw)
    homing.HomingMove.homing_move = _homing_move
toolhead.ToolHead.set_position = _setpos

sys.argv = [os.path.join(kdir, 'klippy.py')] + sys.argv[2:]
import klippy  # noqa: E402
try:
    klippy.main()
finally:
    out.close()
