"""Drive the PyPI package grbl-streamer (a character-counting GRBL 1.1
sender) against a burin port: stream a job with arcs, hold mid-job, check
the hold, resume, change the feed (the sender's own feed override and a
GRBL realtime +10 % sent UTF-8 encoded, as bCNC and cncjs do), then check
the final position from the status report.

usage: python grbl_streamer_job.py PORT JOB X,Y,Z
exit 0 on success; prints one line saying what failed otherwise."""
import sys
import time
import threading

from grbl_streamer import GrblStreamer

port, job, want = sys.argv[1], open(sys.argv[2]).read(), [float(v) for v in sys.argv[3].split(",")]
booted, done, errors, states = threading.Event(), threading.Event(), [], []
processed = [0]
boots = []


def on_event(event, *data):
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
    print("FAIL: " + why)
    sys.exit(1)


g = GrblStreamer(on_event)
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
