// Drive cncjs (npm) against a burin port through its own server: the
// socket.io API its web page uses, its GrblController and its serial
// connection. Streams a job with arcs, holds mid-job (checks Hold), resumes
// (checks Run), sends a feed override +10 % (cncjs writes 0x91 as a string,
// so it leaves as UTF-8 `C2 91`), checks the final position, then jogs and
// cancels the jog (0x85, also UTF-8) and checks that it stopped short.
//
// usage: node cncjs_job.js NPM_DIR PORT JOB X,Y,Z
// exit 0 on success; the last stdout line says what failed otherwise, and
// the exchange with the device (bytes both ways) goes to stderr.
'use strict';
const path = require('path');
const fs = require('fs');
const os = require('os');

const [npmDir, port, jobPath, wantArg] = process.argv.slice(2);
const want = wantArg.split(',').map(Number);
const modules = path.join(path.resolve(npmDir), 'node_modules');
const need = (name) => require(path.join(modules, name));
const job = fs.readFileSync(jobPath, 'utf8');
const t0 = Date.now();
const log = [];
const wire = []; // every byte cncjs wrote to the port
const show = (buf) =>
  Array.from(buf, (b) => (b >= 0x20 && b < 0x7f ? String.fromCharCode(b) : '\\x' + b.toString(16).padStart(2, '0'))).join('');
const note = (what, buf) => log.push(`${((Date.now() - t0) / 1000).toFixed(3)} ${what} ${show(buf)}`);

function fail(why) {
  console.log('FAIL: ' + why);
  const lines = log.length <= 400 ? log : log.slice(0, 300).concat(['...'], log.slice(-100));
  for (const l of lines) process.stderr.write(l + '\n');
  process.exit(1);
}
setTimeout(() => fail('timed out (200 s)'), 200000).unref();

// The server keeps its settings (and the token's secret) in a file of ours,
// not in ~/.cncrc.
const home = fs.mkdtempSync(path.join(os.tmpdir(), 'burin-cncjs-'));
const rc = path.join(home, 'cncrc.json');
const secret = 'burin-senders-check';
process.on('exit', () => fs.rmSync(home, { recursive: true, force: true }));
fs.writeFileSync(rc, JSON.stringify({ secret, state: { checkForUpdates: false } }));

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let state = {}; // the controller's parsed status (cncjs's own parser)
const states = [];
let senderStatus = {};
async function until(what, ms, pred) {
  const end = Date.now() + ms;
  while (Date.now() < end) {
    if (pred()) return;
    await sleep(20);
  }
  fail(`${what} (state ${JSON.stringify(states.slice(-5))})`);
}
const active = () => (state.status || {}).activeState || '';
const mpos = () => {
  const m = (state.status || {}).mpos || {};
  return [Number(m.x), Number(m.y), Number(m.z)];
};

async function main() {
  // cncjs's CLI changes into its server directory before loading it.
  const serverDir = path.join(modules, 'cncjs', 'dist', 'cncjs', 'server');
  process.chdir(serverDir);
  // Tap cncjs's serial connection: the bytes as they go to the port
  // (serialport encodes a string as UTF-8) and each line read back.
  const conn = require(path.join(serverDir, 'lib', 'SerialConnection')).default.prototype;
  const write = conn.write;
  conn.write = function (data, context) {
    if (!this.burinTap) {
      const filter = this.writeFilter;
      this.writeFilter = (d, c) => {
        const out = filter(d, c);
        const buf = Buffer.from(out);
        wire.push(...buf);
        note('>', buf);
        return out;
      };
      this.burinTap = true;
    }
    return write.call(this, data, context);
  };
  const emit = conn.emit;
  conn.emit = function (event, ...args) {
    if (event === 'data') note('<', Buffer.from(String(args[0])));
    return emit.call(this, event, ...args);
  };
  const server = require(serverDir);
  const addr = await new Promise((resolve, reject) =>
    server.createServer(
      { port: 0, host: '127.0.0.1', backlog: 511, configFile: rc, verbosity: 0,
        mountPoints: [], allowRemoteAccess: false, controller: 'Grbl' },
      (err, data) => (err ? reject(err) : resolve(data)),
    ),
  );
  const token = need('jsonwebtoken').sign({ id: '', name: 'burin' }, secret, { expiresIn: '1h' });
  const io = need('socket.io-client');
  const socket = io.connect(`http://127.0.0.1:${addr.port}`, { query: `token=${token}` });
  socket.on('connect_error', (e) => fail('socket.io: ' + e));
  socket.on('error', (e) => fail('socket.io: ' + e));
  socket.on('serialport:error', (e) => fail('serial port: ' + JSON.stringify(e)));
  socket.on('sender:status', (s) => { senderStatus = s; });
  socket.on('controller:state', (type, s) => {
    state = s;
    const a = active();
    if (states[states.length - 1] !== a) states.push(a);
  });
  const call = (...args) =>
    new Promise((resolve) => socket.emit(...args, (err) => (err ? fail(`${args[0]}: ${err}`) : resolve())));
  const command = (...args) => socket.emit('command', port, ...args);

  await new Promise((r) => socket.on('connect', r));
  await call('open', port, { controllerType: 'Grbl', baudrate: 115200 });
  await until('no Idle status after opening the port', 15000, () => active() === 'Idle');

  // The job, with a hold, a resume and an override while it runs.
  await call('command', port, 'gcode:load', 'burin-job.gcode', job, {});
  command('gcode:start');
  await until('job never reached its 3rd line', 30000, () => (senderStatus.received || 0) >= 3);
  command('gcode:pause'); // '!'
  await until('no Hold after gcode:pause', 5000, () => active().startsWith('Hold'));
  await sleep(300);
  const held = mpos();
  await sleep(300);
  if (mpos().some((v, i) => Math.abs(v - held[i]) > 1e-6)) fail(`moved while held: ${held} -> ${mpos()}`);
  command('gcode:resume'); // '~'
  await until('no Run after gcode:resume', 5000, () => active() === 'Run');
  // Overrides outlive a port close (the board has not reset): start at 100 %.
  const feedOv = () => ((state.status || {}).ov || [])[0];
  command('feedOverride', 0); // 0x90
  await until('feed override never showed 100 % after 0x90', 5000, () => feedOv() === 100);
  command('feedOverride', 10); // 0x91, UTF-8 on the wire
  await until('feed override never showed 110 % after 0x91', 5000, () => feedOv() === 110);
  await until('job did not finish', 90000, () =>
    senderStatus.total > 0 && senderStatus.received >= senderStatus.total && active() === 'Idle');
  await sleep(300);
  const end = mpos();
  if (end.some((v, i) => Math.abs(v - want[i]) > 0.01)) fail(`job ended at ${end}, want ${want}`);

  // A slow jog (12 s; the board's clock may run faster than the wall's),
  // cancelled as soon as cncjs shows it.
  command('gcode', '$J=G91 X20 F100');
  await until('no Jog state after $J=', 5000, () => active() === 'Jog');
  command('jogCancel'); // 0x85, UTF-8 on the wire
  await until('jog cancel did not bring Idle', 5000, () => active() === 'Idle');
  await sleep(300);
  const jogged = mpos()[0] - end[0];
  if (!(jogged > 0.01 && jogged < 19.9)) fail(`jog cancel: moved ${jogged} mm in X, want part of 20`);

  const bad = log.find((l) => / < (error|ALARM)/.test(l));
  if (bad) fail(`the device answered ${bad}`);
  const sent = show(wire);
  for (const b of ['\\xc2\\x90', '\\xc2\\x91', '\\xc2\\x85']) {
    if (!sent.includes(b)) fail(`cncjs never wrote ${b}`);
  }
  command('feedOverride', 0);
  await sleep(100);
  socket.emit('close', port);
  await sleep(300);
  console.log(`ok: ended at ${end}; jog cancelled after ${jogged.toFixed(3)} of 20 mm; states ${states.join('>')}`);
  process.exit(0);
}

main().catch((e) => fail(String(e && e.stack ? e.stack : e)));
