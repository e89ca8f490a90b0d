"""Drive the PyPI package grbl-streamer (a character-counting GRBL 1.1
sender) against a burin port: stream a job with arcs, hold mid-job, check
the hold, resume, change the feed (the sender's own feed override and a
GRBL realtime +10 % sent UTF-8 encoded, as bCNC and cncjs do), then check
the final position from the status report.

usage: python grbl_streamer_job.py PORT JOB X,Y,Z
exit 0 on success; prints one line saying what failed otherwise."""
import faulthandler
import os
import sys
import time
import threading

from grbl_streamer import GrblStreamer

port, job, want = sys.argv[1], open(sys.argv[2]).read(), [float(v) for v in sys.argv[3].split(",")]
booted, done, errors, states = threading.Event(), threading.Event(), [], []
processed = [0]
boots = []
log = []  # what went each way, for the failure report


def on_event(event, *data):
    if event in ("on_write", "on_read", "on_stateupdate", "on_boot", "on_job_completed"):
        log.append("%.3f %s %r" % (time.time(), event, data))
    if event == "on_boot":
        boots.append(time.time())
        booted.set()
    elif event == "on_job_completed":
        done.set()
    elif event in ("on_error", "on_alarm"):
        errors.append((event, data))
    elif event == "on_stateupdate":
        states.append(data[0])
    elif event == "on_processed_command":
        processed[0] += 1


def fail(why):
    # The sender's reader and poller threads are not daemons: sys.exit
    # would wait on them for ever and hide this line behind a timeout.
    print("FAIL: " + why, flush=True)
    # The first exchange and the last: a stuck run repeats one status.
    for entry in (log if len(log) <= 300 else log[:240] + ["..."] + log[-60:]):
        print(entry, file=sys.stderr)
    sys.stderr.flush()
    os._exit(1)


# Were anything to block past the runner's limit, say where.
faulthandler.dump_traceback_later(200, exit=True)
g = GrblStreamer(on_event)
_update_state = g._update_state


def logged_update_state(line):
    log.append("%.3f status %s" % (time.time(), line))
    _update_state(line)


g._update_state = logged_update_state
g.cnect(port, 115200)
if not booted.wait(10):
    fail("no boot banner")
# Opening the port prints a banner and so does the sender's own Ctrl-X
# right after it; grbl-streamer treats each banner as a fresh boot and
# marks any job it is streaming as finished. Start once the banners stop.
deadline = time.time() + 10
while time.time() < boots[-1] + 1.0 and time.time() < deadline:
    time.sleep(0.05)
g.poll_interval = 0.05
g.poll_start()
g.incremental_streaming = True
g.set_feed_override(True)
g.request_feed(1500)
g.write(job)
g.job_run()
# Mid-job: hold, check, resume, override.
deadline = time.time() + 30
while processed[0] < 3 and time.time() < deadline:
    time.sleep(0.01)
g.hold()
time.sleep(0.5)
if not any(s.startswith("Hold") for s in states[-5:]):
    fail("no Hold state after '!': %s" % states[-5:])
g.resume()
g.request_feed(2000)
g._iface.serialport.write(b"\xc2\x91")  # feed +10 %, UTF-8 form
if not done.wait(60):
    fail("job not completed (%d commands processed)" % processed[0])
deadline = time.time() + 30
while time.time() < deadline:
    time.sleep(0.1)
    if states and states[-1] == "Idle":
        break
else:
    fail("never idle: %s" % states[-3:])
time.sleep(0.2)
pos = list(g.cmpos)
g.poll_stop()
g.disconnect()
if errors:
    fail("errors: %s" % errors)
if len(boots) > 2:
    fail("%d boot banners, want at most 2 (port open, Ctrl-X)" % len(boots))
if any(abs(a - b) > 0.01 for a, b in zip(pos, want)):
    fail("ended at %s, want %s" % (pos, want))
print("ok: ended at %s (%d boot banners)" % (pos, len(boots)))
