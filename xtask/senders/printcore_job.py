"""Drive printcore (PyPI package printrun, the host core of Pronterface)
against a burin port: it opens with `N-1 M110 N-1*125`, streams the job
with RepRap line numbers and checksums, send-response. One line goes out
with a damaged checksum the first time (a line hit by noise): burin must
ask for it again with `Resend:` and run it once. Then the final position
is read from a `?` status report.

usage: python printcore_job.py PORT JOB X,Y,Z
exit 0 on success; prints one line saying what failed otherwise, and the
exchange with the device (bytes both ways) on stderr."""
import faulthandler
import os
import sys
import time

from printrun.printcore import printcore
from printrun import gcoder

port, job, want = sys.argv[1], open(sys.argv[2]).read(), [float(v) for v in sys.argv[3].split(",")]
lines, errors, resends = [], [], []
t0 = time.time()
log = []  # the exchange, for the failure report


def note(way, data):
    text = "".join(chr(b) if 0x20 <= b < 0x7F else "\\x%02x" % b for b in data)
    log.append("%.3f %s %s" % (time.time() - t0, way, text))


def fail(why):
    # printcore's threads would keep sys.exit waiting: leave at once.
    print("FAIL: " + why, flush=True)
    for entry in log if len(log) <= 400 else log[:300] + ["..."] + log[-100:]:
        print(entry, file=sys.stderr)
    sys.stderr.flush()
    os._exit(1)


# Were anything to block past the runner's limit, say where.
faulthandler.dump_traceback_later(200, exit=True)


def on_recv(line):
    note("<", line.encode())
    line = line.strip()
    lines.append(line)
    if line.lower().startswith("error"):
        errors.append(line)
    if line.startswith("Resend"):
        resends.append(line)


p = printcore()
p.recvcb = on_recv
p.connect(port, 115200)
deadline = time.time() + 20
while not p.online and time.time() < deadline:
    time.sleep(0.05)
if not p.online:
    fail("never online")
# Noise: the first time line N3 goes out, one digit of its checksum flips.
write = p.printer.write
damaged = []


def noisy_write(data):
    if data.startswith(b"N3 ") and not damaged:
        damaged.append(data)
        head, _, _ = data.rpartition(b"*")
        data = head + b"*0\n" if not data.endswith(b"*0\n") else head + b"*1\n"
    note(">", data)
    return write(data)


p.printer.write = noisy_write
# printcore's online probe (M105, a temperature query) is no GRBL command.
time.sleep(0.5)
errors.clear()
p.startprint(gcoder.LightGCode(job.splitlines()))
deadline = time.time() + 120
while p.printing and time.time() < deadline:
    time.sleep(0.05)
if p.printing:
    fail("print never finished (%d lines back)" % len(lines))
pos = None
deadline = time.time() + 60
while time.time() < deadline:
    p.send_now("?")
    time.sleep(0.2)
    st = [l for l in lines if l.startswith("<")]
    if st and st[-1].startswith("<Idle"):
        mpos = st[-1].split("MPos:")[1].split("|")[0].split(",")
        pos = [float(v) for v in mpos[:3]]
        break
p.disconnect()
if pos is None:
    fail("never idle")
if not damaged or resends != ["Resend: 3"]:
    fail("damaged line %s, resends %s" % (damaged, resends))
if any(not e.startswith("Error:checksum mismatch") for e in errors):
    fail("errors: %s" % errors)
if any(abs(a - b) > 0.01 for a, b in zip(pos, want)):
    fail("ended at %s, want %s" % (pos, want))
print("ok: ended at %s after a resend" % pos)
