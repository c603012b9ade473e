// deflex live view: hand-written on uPlot (charts) and three.js (3-D path), both vendored.
// Data arrives over the page's WebSocket: a JSON hello (session, wire layout, names), then
// binary messages of buckets (16-byte header: kind, count, values per bucket, frames dropped
// for this page; then count × values little-endian f64, in the hello's field order).
import * as THREE from "three";
import { OrbitControls } from "/vendor/three/OrbitControls.js";

const KIND_HISTORY = 1;
const KIND_LIVE = 2;
const COLORS = { x: "#d32f2f", y: "#388e3c", z: "#1565c0", n: "#212121", a: "#8e24aa", b: "#ef6c00" };

// State the page keeps, exposed for tests and curious operators (window.deflexView).
const view = {
  hello: null,
  connected: false,
  messages: 0,
  buckets: 0,
  draws: 0,
  drawTimes: [],
  updateHz: 0,
  droppedForPage: 0,
  last: null,
  windowS: 600,
  webgl: null,
  stopSent: 0,
};
window.deflexView = view;
// Points held by each chart (for tests).
view.chartLengths = () => Object.fromEntries(Object.entries(charts).map(([k, c]) => [k, c.data[0].length]));

let fieldIndex = {};
let maxBuckets = 15000;
let dirty = false;

// ---------------------------------------------------------------- charts
// Each chart: series of [field, scale, label, colour, dash]; the x values are session time.
const CHARTS = {
  force: { el: "c-force", unit: "N", series: [
    ["fx_n", 1, "Fx", COLORS.x], ["fy_n", 1, "Fy", COLORS.y], ["fz_n", 1, "Fz", COLORS.z],
    ["f_norm_max_n", 1, "|F| (max in bucket)", COLORS.n]] },
  torque: { el: "c-torque", unit: "N·m", series: [
    ["mx_nm", 1, "Mx", COLORS.x], ["my_nm", 1, "My", COLORS.y], ["mz_nm", 1, "Mz", COLORS.z]] },
  deflection: { el: "c-deflection", unit: "mm", series: [
    ["ds_x_m", 1e3, "δŝ x", COLORS.x], ["ds_y_m", 1e3, "δŝ y", COLORS.y], ["ds_z_m", 1e3, "δŝ z", COLORS.z]] },
  correction: { el: "c-correction", unit: "mm", series: [
    ["xi_x_m", 1e3, "ξ x", COLORS.x], ["xi_y_m", 1e3, "ξ y", COLORS.y], ["xi_z_m", 1e3, "ξ z", COLORS.z]] },
  error: { el: "c-error", unit: "mm", series: [
    ["err_x_m", 1e3, "x", COLORS.x], ["err_y_m", 1e3, "y", COLORS.y], ["err_z_m", 1e3, "z", COLORS.z],
    ["err_norm_m", 1e3, "norm", COLORS.n]] },
  timing: { el: "c-timing", unit: "µs", series: [
    ["cycle_time_max_s", 1e6, "cycle time (max in bucket)", COLORS.a],
    ["cycle_time_p99_s", 1e6, "p99, last cycles", COLORS.b]] },
};

// The digital twin's own stream (`deflex cell --sim`, `deflex sim isf` open loop) carries the
// ground truth where a controller's stream carries its estimates: its panels say so.
const TWIN_CELL = {
  titles: {
    "h-force": "True contact force at the TCP, base axes (N)",
    "h-torque": "True contact torque at the TCP, base axes (N·m)",
    "h-deflection": "True deflection of the arm at the TCP (mm)",
    "h-correction": "Correction ξ the robot applies (mm) against its bounds",
    "h-timing": "Round trip of the controller's answers (µs)",
    "h-three": "TCP path, base frame: program, commanded by the robot, and true",
  },
  labels: {
    ds_x_m: "δs x", ds_y_m: "δs y", ds_z_m: "δs z",
    cycle_time_max_s: "round trip (max in bucket)", cycle_time_p99_s: "p99, last samples",
  },
};
let defaultTitles = null;

function applySourceTexts(twinCell) {
  if (!defaultTitles) {
    defaultTitles = {};
    for (const id of Object.keys(TWIN_CELL.titles)) defaultTitles[id] = document.getElementById(id).textContent;
  }
  for (const [id, text] of Object.entries(TWIN_CELL.titles)) {
    setText(id, twinCell ? text : defaultTitles[id]);
  }
}

const charts = {};
const columns = {}; // chart name -> arrays [t, s1, s2, ...]
const constants = {}; // chart name -> values of its constant (limit) lines

function makeChart(name, spec, extra) {
  const el = document.getElementById(spec.el);
  const series = [{ label: "t (s)" }];
  const twinCell = view.hello.session.source === "twin-cell";
  for (const [field, , label, stroke, dash] of spec.series) {
    const shown = (twinCell && TWIN_CELL.labels[field]) || label;
    series.push({ label: shown, stroke, width: 1.5, dash, spanGaps: false });
  }
  for (const e of extra) series.push({ label: e.label, stroke: e.stroke, dash: e.dash, width: e.width });
  constants[name] = extra.map((e) => e.value);
  const opts = {
    width: Math.max(300, el.clientWidth),
    height: 220,
    series,
    scales: { x: { time: false } },
    axes: [{ label: "session time (s)", size: 40 }, { label: spec.unit, size: 60 }],
    legend: { live: false },
    cursor: { drag: { x: false, y: false } },
  };
  const data = series.map(() => []);
  columns[name] = data;
  charts[name] = new uPlot(opts, data, el);
}

function resetCharts() {
  for (const c of Object.values(charts)) c.destroy();
  for (const k of Object.keys(charts)) delete charts[k];
  const limits = view.hello.session.correction_limit;
  const forceLimit = view.hello.session.force_limit_n;
  for (const [name, spec] of Object.entries(CHARTS)) {
    const extra = [];
    if (name === "correction") {
      // ±limit of the position axes (the largest of x, y, z), dashed.
      const l = Math.max(...limits.slice(0, 3).map((v) => (v == null ? 0 : v)));
      if (l > 0) {
        extra.push({ label: "+limit", stroke: "#c62828", dash: [6, 4], width: 1, value: l * 1e3 });
        extra.push({ label: "−limit", stroke: "#c62828", dash: [6, 4], width: 1, value: -l * 1e3 });
      }
    }
    if (name === "force" && forceLimit != null) {
      extra.push({ label: "|F| limit", stroke: "#c62828", dash: [6, 4], width: 1, value: forceLimit });
    }
    makeChart(name, spec, extra);
  }
  const source = view.hello.session.source;
  const known = source === "twin" || source === "twin-cell";
  document.getElementById("error-unknown").hidden = known;
  document.getElementById("c-error").hidden = !known;
  document.getElementById("legend-true").hidden = !known;
  applySourceTexts(source === "twin-cell");
}

function appendBucket(values) {
  const t = values[fieldIndex.t_s];
  for (const [name, spec] of Object.entries(CHARTS)) {
    const data = columns[name];
    const lines = constants[name];
    data[0].push(t);
    spec.series.forEach(([field, scale], i) => {
      const v = values[fieldIndex[field]];
      data[i + 1].push(Number.isFinite(v) ? v * scale : null);
    });
    lines.forEach((v, j) => data[spec.series.length + 1 + j].push(v));
  }
  track3d(values);
  view.last = values;
  view.buckets++;
}

function trimColumns() {
  for (const data of Object.values(columns)) {
    const excess = data[0].length - maxBuckets;
    if (excess > 250) for (const a of data) a.splice(0, excess);
  }
}

// ---------------------------------------------------------------- 3-D path
const three = { ok: false, n: 0 };

function init3d() {
  const host = document.getElementById("three");
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    host.innerHTML = "<p class='muted'>The 3-D view needs WebGL, which this browser does not offer.</p>";
    view.webgl = false;
    console.warn("deflex view: no WebGL, 3-D view off");
    return;
  }
  view.webgl = true;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(host.clientWidth, host.clientHeight);
  renderer.setClearColor(0xffffff);
  host.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(45, host.clientWidth / host.clientHeight, 0.1, 1e5);
  camera.up.set(0, 0, 1);
  camera.position.set(150, -150, 120);
  const controls = new OrbitControls(camera, renderer.domElement);
  const cap = maxBuckets + 300;
  const make = (color) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(new Float32Array(cap * 3), 3));
    g.setDrawRange(0, 0);
    const line = new THREE.Line(g, new THREE.LineBasicMaterial({ color }));
    line.frustumCulled = false;
    scene.add(line);
    return g;
  };
  const program = make(0x546e7a);
  const corrected = make(0xef6c00);
  const truth = make(0x2e7d32);
  const marker = new THREE.Mesh(new THREE.SphereGeometry(1.2, 16, 12), new THREE.MeshBasicMaterial({ color: 0xef6c00 }));
  scene.add(marker);
  scene.add(new THREE.AxesHelper(20));
  Object.assign(three, { ok: true, renderer, scene, camera, controls, program, corrected, truth, marker, cap,
    origin: null, prog: [], corr: [], err: [], fitted: false });
  document.getElementById("fit").onclick = () => fit3d();
  document.getElementById("exaggerate").onchange = () => { rebuild3d(); fit3d(); dirty = true; };
  new ResizeObserver(() => {
    renderer.setSize(host.clientWidth, host.clientHeight);
    camera.aspect = host.clientWidth / host.clientHeight;
    camera.updateProjectionMatrix();
    dirty = true;
  }).observe(host);
}

function track3d(values) {
  if (!three.ok) return;
  const p = [values[fieldIndex.prog_x_m], values[fieldIndex.prog_y_m], values[fieldIndex.prog_z_m]];
  const c = [values[fieldIndex.tcp_x_m], values[fieldIndex.tcp_y_m], values[fieldIndex.tcp_z_m]];
  if (!p.every(Number.isFinite) || !c.every(Number.isFinite)) return;
  // mm, relative to the first point (float32 keeps µm there).
  if (!three.origin) three.origin = p.slice();
  three.prog.push(p.map((v, i) => (v - three.origin[i]) * 1e3));
  three.corr.push(c.map((v, i) => (v - p[i]) * 1e3));
  // The twin's true TCP: the program plus the path error (true − desired), when known.
  const e = [values[fieldIndex.err_x_m], values[fieldIndex.err_y_m], values[fieldIndex.err_z_m]];
  three.err.push(e.every(Number.isFinite) ? e.map((v) => v * 1e3) : null);
  if (three.prog.length > three.cap) {
    three.prog.splice(0, 300);
    three.corr.splice(0, 300);
    three.err.splice(0, 300);
  }
  three.stale = true;
}

function rebuild3d() {
  if (!three.ok) return;
  const k = Number(document.getElementById("exaggerate").value);
  const pa = three.program.attributes.position.array;
  const ca = three.corrected.attributes.position.array;
  const ta = three.truth.attributes.position.array;
  const n = three.prog.length;
  let nt = 0;
  for (let i = 0; i < n; i++) {
    const p = three.prog[i], d = three.corr[i], e = three.err[i];
    for (let j = 0; j < 3; j++) {
      pa[3 * i + j] = p[j];
      ca[3 * i + j] = p[j] + k * d[j];
    }
    if (e) {
      for (let j = 0; j < 3; j++) ta[3 * nt + j] = p[j] + k * e[j];
      nt++;
    }
  }
  three.program.attributes.position.needsUpdate = true;
  three.corrected.attributes.position.needsUpdate = true;
  three.truth.attributes.position.needsUpdate = true;
  three.program.setDrawRange(0, n);
  three.corrected.setDrawRange(0, n);
  three.truth.setDrawRange(0, nt);
  if (n > 0) three.marker.position.set(ca[3 * n - 3], ca[3 * n - 2], ca[3 * n - 1]);
  three.n = n;
  three.stale = false;
  if (!three.fitted && n > 20) fit3d();
}

function fit3d() {
  if (!three.ok || three.n === 0) return;
  // Both paths (the corrected one as exaggerated) inside the view.
  const box = new THREE.Box3();
  for (const g of [three.program, three.corrected, three.truth]) {
    g.computeBoundingBox();
    box.union(g.boundingBox);
  }
  const s = box.getBoundingSphere(new THREE.Sphere());
  const r = Math.max(s.radius, 5);
  three.controls.target.copy(s.center);
  three.camera.position.set(s.center.x + 1.6 * r, s.center.y - 1.6 * r, s.center.z + 1.2 * r);
  three.controls.update();
  three.fitted = true;
}

// ---------------------------------------------------------------- text panels
function setText(id, text) {
  const el = document.getElementById(id);
  if (el.textContent !== text) el.textContent = text;
}

function showState(values) {
  const h = view.hello;
  const phase = h.phases[values[fieldIndex.phase]] ?? "?";
  const el = document.getElementById("phase");
  el.className = "badge " + phase;
  setText("phase", (h.session.source === "twin-cell" ? "cell: " : "phase: ") + phase);
  const faultCode = values[fieldIndex.fault];
  const fault = document.getElementById("fault");
  fault.hidden = !(faultCode > 0);
  if (faultCode > 0) setText("fault", "fault: " + (h.faults[faultCode - 1] ?? faultCode));
  const flags = values[fieldIndex.flags] >>> 0;
  const names = h.flags.filter(([bit]) => (flags >>> bit) & 1).map(([bit, name]) => [bit, name]);
  const html = names.map(([bit, name]) => {
    const cls = bit < 16 || name === "latched" ? "bad" : (name.startsWith("saturated") || name === "runaway_hold" ? "warn" : "");
    return `<span class="${cls}">${name}</span>`;
  }).join("");
  const flagsEl = document.getElementById("flags");
  if (flagsEl.innerHTML !== html) flagsEl.innerHTML = html;

  // |ξ_i| against its limit, per axis.
  const limits = h.session.correction_limit;
  const axes = ["x", "y", "z", "rx", "ry", "rz"];
  const rows = axes.map((a, i) => {
    const v = values[fieldIndex["xi_" + a + (i < 3 ? "_m" : "_rad")]];
    const l = limits[i];
    const unit = i < 3 ? "mm" : "mrad";
    const frac = l ? Math.min(1, Math.abs(v) / l) : 0;
    const cls = frac >= 0.999 ? "full" : frac > 0.8 ? "high" : "";
    const lim = l ? (l * 1e3).toFixed(1) : "∞";
    return `<tr><td>ξ ${a}</td><td>${(v * 1e3).toFixed(3)} ${unit}</td>` +
      `<td class="bar"><div><i class="${cls}" style="width:${(frac * 100).toFixed(1)}%"></i></div></td>` +
      `<td>limit ${lim} ${unit}</td></tr>`;
  }).join("");
  const table = document.getElementById("limits");
  if (table.innerHTML !== rows) table.innerHTML = rows;

  const fmt = (v, d = 0) => (Number.isFinite(v) ? v.toFixed(d) : "–");
  const twinCell = h.session.source === "twin-cell";
  const counters = [
    [twinCell ? "robot cycle" : "cycle", fmt(values[fieldIndex.cycle])],
    ["time (s)", fmt(values[fieldIndex.t_s], 2)],
    [twinCell ? "round trip (µs)" : "cycle time (µs)", fmt(values[fieldIndex.cycle_time_s] * 1e6, 0)],
    ["p99 (µs)", fmt(values[fieldIndex.cycle_time_p99_s] * 1e6, 0)],
    ["late answers", fmt(values[fieldIndex.late_answers])],
    ["robot's late count", fmt(values[fieldIndex.robot_late])],
    ["view samples lost", fmt(values[fieldIndex.view_lost])],
    ["messages dropped for this page", String(view.droppedForPage)],
    ["|F| (N)", fmt(values[fieldIndex.f_norm_n], 1)],
    ["loop gain", fmt(values[fieldIndex.loop_gain], 3)],
  ].map(([k, v]) => `<dt>${k}</dt><dd>${v}</dd>`).join("");
  const dl = document.getElementById("counters");
  if (dl.innerHTML !== counters) dl.innerHTML = counters;
}

// ---------------------------------------------------------------- drawing
function draw(now) {
  requestAnimationFrame(draw);
  if (!dirty || !view.hello) return;
  dirty = false;
  trimColumns();
  let tmax = -Infinity;
  for (const [name, chart] of Object.entries(charts)) {
    const data = columns[name];
    if (data[0].length) tmax = Math.max(tmax, data[0][data[0].length - 1]);
    chart.setData(data, false);
  }
  if (Number.isFinite(tmax)) {
    const tmin = tmax - view.windowS;
    for (const chart of Object.values(charts)) chart.setScale("x", { min: Math.max(tmin, chart.data[0][0] ?? tmin), max: tmax });
  }
  if (three.ok) {
    if (three.stale) rebuild3d();
    three.controls.update();
    three.renderer.render(three.scene, three.camera);
  }
  if (view.last) showState(view.last);
  view.draws++;
  view.drawTimes.push(now);
  while (view.drawTimes.length && view.drawTimes[0] < now - 2000) view.drawTimes.shift();
  view.updateHz = view.drawTimes.length / 2;
  setText("rate", view.updateHz.toFixed(1) + " updates/s");
}

// ---------------------------------------------------------------- connection
function onHello(h) {
  view.hello = h;
  fieldIndex = {};
  h.fields.forEach((f, i) => { fieldIndex[f] = i; });
  maxBuckets = Math.round(h.window_s / h.bucket_s);
  view.windowS = h.window_s;
  document.getElementById("label").hidden = h.label !== "SIMULATED";
  setText("robot", `${h.session.robot} · ${h.session.source} · ${h.session.protocol}`);
  document.title = (h.label ? h.label + " " : "") + "deflex live view: " + h.session.robot;
  document.getElementById("stop").hidden = !h.stop;
  resetCharts();
  if (three.ok) { three.prog = []; three.corr = []; three.err = []; three.origin = null; three.fitted = false; three.stale = true; }
}

function onBinary(buffer) {
  if (!view.hello || buffer.byteLength < 16) return;
  const header = new DataView(buffer, 0, 16);
  const kind = header.getUint32(0, true);
  const count = header.getUint32(4, true);
  const nf = header.getUint32(8, true);
  view.droppedForPage = header.getUint32(12, true);
  if ((kind !== KIND_HISTORY && kind !== KIND_LIVE) || nf !== view.hello.fields.length ||
      buffer.byteLength !== 16 + count * nf * 8) {
    console.warn("deflex view: unexpected message", kind, count, nf, buffer.byteLength);
    return;
  }
  const values = new Float64Array(buffer, 16, count * nf);
  for (let i = 0; i < count; i++) appendBucket(values.subarray(i * nf, (i + 1) * nf));
  view.messages++;
  dirty = true;
}

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.binaryType = "arraybuffer";
  const status = document.getElementById("connection");
  ws.onopen = () => { view.connected = true; status.className = "badge on"; status.textContent = "live"; };
  ws.onclose = () => {
    view.connected = false;
    status.className = "badge off";
    status.textContent = "disconnected: retrying";
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === "string") {
      const msg = JSON.parse(ev.data);
      if (msg.type === "hello") onHello(msg);
      else if (msg.type === "stop_ack") setText("stop", "Stop requested (ramping out)");
      else if (msg.type === "error") console.warn("deflex view:", msg.message);
    } else {
      onBinary(ev.data);
    }
  };
  view.socket = ws;
}

document.querySelectorAll("[data-window]").forEach((b) => {
  b.onclick = () => {
    view.windowS = Number(b.dataset.window);
    document.querySelectorAll("[data-window]").forEach((o) => o.classList.toggle("on", o === b));
    dirty = true;
  };
});

document.getElementById("stop").onclick = () => {
  const ok = window.confirm(
    "Stop the correction?\n\nThe controller ramps the correction out (the same safe stop as Ctrl-C) " +
    "and the robot returns to its programmed path.");
  if (ok && view.socket && view.socket.readyState === WebSocket.OPEN) {
    view.socket.send(JSON.stringify({ cmd: "stop" }));
    view.stopSent++;
  }
};

window.addEventListener("resize", () => {
  for (const [name, chart] of Object.entries(charts)) {
    const el = document.getElementById(CHARTS[name].el);
    chart.setSize({ width: Math.max(300, el.clientWidth), height: 220 });
  }
});

init3d();
connect();
requestAnimationFrame(draw);
