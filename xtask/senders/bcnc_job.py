"""Drive bCNC (Debian package `bcnc`) against a burin port through its own
sender: `Sender.Sender` (the serial thread, character counting, the GRBL1
controller plugin) and `GCode.compile`, as its Run button does, without
the Tk window (these modules import tkinter but need no display). Streams a
job with arcs, holds mid-job (checks Hold, no motion), resumes (checks
Run), moves the feed override slider to 110 % (bCNC writes chr(0x91)
encoded, so it leaves as UTF-8 `C2 91`), checks the final position after
bCNC's end-of-job purge (`!`, Ctrl-X, `$X`), then jogs with its jog
command and cancels with its terminal's `SENDHEX 85` (`C2 85` on the wire)
and checks that the jog stopped short.

usage: /usr/bin/python3 bcnc_job.py BCNC_DIR PORT JOB X,Y,Z
exit 0 on success; the last stdout line says what failed otherwise, and
the exchange with the device (bytes both ways) goes to stderr."""
import faulthandler
import os
import shutil
import sys
import tempfile
import threading
import time

bcnc, port, job, want = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
want = [float(v) for v in want.split(",")]
# bCNC reads and writes ~/.bCNC: keep ours apart from the user's.
os.environ["HOME"] = tempfile.mkdtemp(prefix="burin-bcnc-")
for sub in ("", "lib", "plugins", "controllers"):
    sys.path.insert(0, os.path.join(bcnc, sub))

t0 = time.time()
log = []  # the exchange, for the failure report
lock = threading.Lock()


def show(data):
    return "".join(chr(b) if 0x20 <= b < 0x7F else "\\x%02x" % b for b in data)


def note(way, data):
    with lock:
        log.append("%.3f %s %s" % (time.time() - t0, way, show(data)))


restore = []  # settings to put back, even when failing


def leave(code):
    shutil.rmtree(os.environ["HOME"], ignore_errors=True)
    # bCNC's serial thread is not a daemon: exit without waiting for it.
    os._exit(code)


def fail(why):
    print("FAIL: " + why, flush=True)
    for line in restore:
        try:
            s.serial.write(line)
            time.sleep(0.2)
        except Exception:
            pass
    with lock:
        lines = log if len(log) <= 400 else log[:300] + ["..."] + log[-100:]
        for entry in lines:
            print(entry, file=sys.stderr)
    sys.stderr.flush()
    leave(1)


faulthandler.dump_traceback_later(200, exit=True)

import serial  # noqa: E402  (Debian's python3-serial, as bCNC uses it)

_serial_for_url = serial.serial_for_url


class Tap:
    """bCNC's port, recording every byte written and every line read."""

    def __init__(self, inner):
        self._inner = inner

    def write(self, data):
        note(">", data)
        return self._inner.write(data)

    def readline(self):
        line = self._inner.readline()
        if line:
            note("<", line)
        return line

    def __getattr__(self, name):
        return getattr(self._inner, name)


serial.serial_for_url = lambda *a, **k: Tap(_serial_for_url(*a, **k))

import Utils  # noqa: E402

Utils.loadConfiguration()
import Sender  # noqa: E402
from CNC import CNC, WAIT  # noqa: E402


class Headless(Sender.Sender):
    """The application class minus its widgets (`disable` greys them)."""

    def disable(self):
        pass

    def enable(self):
        pass


def until(what, secs, pred):
    end = time.time() + secs
    while time.time() < end:
        if pred():
            return
        time.sleep(0.02)
    fail("%s (bCNC state %r)" % (what, CNC.vars["state"]))


def mpos():
    return [CNC.vars["mx"], CNC.vars["my"], CNC.vars["mz"]]


s = Headless()
if s.controller != "GRBL1":
    fail("bCNC has no GRBL1 controller plugin (%s)" % s.controller)
s.open(port, 115200)
until("no Idle status after opening the port", 15, lambda: CNC.vars["state"] == "Idle")

# Overrides outlive a port close (the board has not reset): start at 100 %.
s.executeCommand("SENDHEX 90")
until("feed override not back to 100 % after 0x90", 10, lambda: CNC.vars["OvFeed"] == 100)

# The Run button (bCNC.Application.run), minus its canvas.
s.gcode.load(job)
s.cleanAfter = True
s.initRun()
s._runLines = sys.maxsize
s._gcount = 0
CNC.vars["running"] = True
CNC.vars["_OvChanged"] = True
paths = s.gcode.compile(s.queue, lambda: False)
if not paths:
    fail("bCNC compiled no lines from %s" % job)
s._runLines = len(paths) + 1
s.queue.put((WAIT,))

until("job never reached its 3rd line", 30, lambda: s._gcount >= 3)
s.feedHold()  # '!'
until("no Hold after bCNC's feed hold", 5, lambda: CNC.vars["state"].startswith("Hold"))
time.sleep(0.4)
held = mpos()
time.sleep(0.4)
if mpos() != held:
    fail("moved while held: %s -> %s" % (held, mpos()))
s.resume()  # '~'
until("no Run after bCNC's resume", 5, lambda: CNC.vars["state"] == "Run")
CNC.vars["_OvFeed"] = 110  # the override slider (ControlPage.overrideChange)
CNC.vars["_OvChanged"] = True
until("feed override never showed 110 %", 10, lambda: CNC.vars["OvFeed"] == 110)


def finished():
    # Application._monitorSerial ends the run once every line is counted.
    if s.running and s._gcount >= s._runLines:
        s.runEnded()
    return not s.running


deadline = time.time() + 90
while not finished():
    if time.time() > deadline:
        fail("job did not finish (%d of %d lines acknowledged)" % (s._gcount, s._runLines))
    time.sleep(0.02)
# bCNC purges the controller when the job ends: '!', 1 s, Ctrl-X, 1 s, $X
# (which its queue drops on the banner), then $G. The position must stay.
def after_reset():
    with lock:
        resets = [i for i, e in enumerate(log) if " > " in e and "\\x18" in e]
        return log[resets[0] :] if resets else []


until("bCNC sent no Ctrl-X after the job", 20, after_reset)
until("no banner after bCNC's Ctrl-X", 10, lambda: any(" < Grbl " in e for e in after_reset()))
time.sleep(0.5)
until("no Idle after bCNC's end-of-job purge", 10, lambda: CNC.vars["state"] == "Idle")
end = mpos()
if any(abs(a - b) > 0.01 for a, b in zip(end, want)):
    fail("job ended at %s, want %s" % (end, want))

# A jog (ControlPage's X+ button with a 100 mm step), cancelled as soon as
# bCNC shows it. The button asks F100000, which GRBL clamps to the axis's
# maximum rate: lower $110 for the jog (the board's clock may run faster
# than the wall's), so that it lasts long enough to be cancelled.
s.viewSettings()  # $$
until("no $110 in the $$ reply", 5, lambda: "grbl_110" in CNC.vars)
max_rate = CNC.vars["grbl_110"]
restore.append(("$110=%s\n" % max_rate).encode())
s.sendGCode("$110=60")
until("$110=60 not taken", 5, lambda: CNC.vars["state"] == "Idle" and s.queue.empty())
time.sleep(0.3)
s.mcontrol.jog("X100")  # $J=G91 X100 F100000
until("no Jog state after $J=", 5, lambda: CNC.vars["state"] == "Jog")
s.executeCommand("SENDHEX 85")  # jog cancel
until("jog cancel did not bring Idle", 5, lambda: CNC.vars["state"] == "Idle")
time.sleep(0.3)
jogged = CNC.vars["mx"] - end[0]
s.sendGCode("$110=%s" % max_rate)
restore.clear()
time.sleep(0.3)
if not 0.01 < jogged < 99.9:
    fail("jog cancel: moved %.3f mm in X, want part of 100" % jogged)

with lock:
    sent = "".join(entry.split(" ", 2)[2] for entry in log if " > " in entry)
    bad = [e for e in log if " < error" in e or " < ALARM" in e]
if bad:
    fail("the device answered %s" % bad[0])
for seq in ("\\xc2\\x90", "\\xc2\\x91", "\\xc2\\x85"):
    if seq not in sent:
        fail("bCNC never wrote %s" % seq)
s.thread = None  # ends bCNC's serial loop
time.sleep(0.3)
s.serial.close()
print("ok: ended at %s; jog cancelled after %.3f of 100 mm" % (end, jogged))
leave(0)
