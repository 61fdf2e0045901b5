// bikerider serve: the page.  Plain JavaScript, no library: the server computes, this file draws (SVG).
"use strict";

const state = { cells: null, steerEdit: null, name: "bicycle", speed: 5.0, map: { x: "c", y: "" }, gains: null, last: null,
  pending: null, busy: false, latencies: [], breakdown: [], sequence: 0, mcTimer: null, mcDone: 0, gapFolder: null, gapJob: null };
window.bikerider = state;  // the browser test reads state.latencies

const COLOURS = { weave: "#1f77b4", capsize: "#d62728", castor: "#2ca02c", other: "#7f7f7f" };
const BODY = { R: "#555555", B: "#1f77b4", H: "#d62728", F: "#555555", T: "#000000" };
const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";

function el(tag, attrs, parent, text) {
  const node = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  if (parent) parent.appendChild(node);
  return node;
}
function html(tag, attrs, parent, text) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  if (parent) parent.appendChild(node);
  return node;
}
function fmt(x, digits = 4) {
  if (x === null || x === undefined || !isFinite(x)) return "n/a";
  return String(Number(Number(x).toPrecision(digits)));
}

async function api(path, body) {
  const options = body === undefined ? {} : { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) };
  const response = await fetch(path, options);
  const data = await response.json();
  if (!response.ok) throw new Error(data.error || response.statusText);
  return data;
}

// ---------------------------------------------------------------- plotting (SVG)
function niceTicks(lo, hi, n = 6) {
  if (!(hi > lo)) { hi = lo + 1; }
  const raw = (hi - lo) / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= raw);
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) ticks.push(Math.abs(t) < step * 1e-9 ? 0 : t);
  return ticks;
}

// An axes box in an SVG: linear (or log-x) scales, grid lines, tick labels, axis labels.
function axes(svg, box, xlim, ylim, opts = {}) {
  const [x0, y0, w, h] = box;
  const logx = !!opts.logx;
  const fx = logx ? (x) => x0 + (Math.log10(x) - Math.log10(xlim[0])) / (Math.log10(xlim[1]) - Math.log10(xlim[0])) * w
    : (x) => x0 + (x - xlim[0]) / (xlim[1] - xlim[0]) * w;
  const fy = (y) => y0 + h - (y - ylim[0]) / (ylim[1] - ylim[0]) * h;
  const g = el("g", {}, svg);
  const clipId = "clip" + Math.random().toString(36).slice(2);
  const clip = el("clipPath", { id: clipId }, g);
  el("rect", { x: x0, y: y0, width: w, height: h }, clip);
  const xt = logx ? [0.1, 1, 10, 100].filter((t) => t >= xlim[0] && t <= xlim[1]) : niceTicks(xlim[0], xlim[1], opts.xticks || 8);
  for (const t of xt) {
    el("line", { x1: fx(t), x2: fx(t), y1: y0, y2: y0 + h, stroke: "#e6e6e6" }, g);
    el("text", { x: fx(t), y: y0 + h + 13, "text-anchor": "middle" }, g, fmt(t, 3));
  }
  for (const t of niceTicks(ylim[0], ylim[1], opts.yticks || 6)) {
    el("line", { x1: x0, x2: x0 + w, y1: fy(t), y2: fy(t), stroke: t === 0 ? "#999" : "#e6e6e6" }, g);
    el("text", { x: x0 - 4, y: fy(t) + 4, "text-anchor": "end" }, g, fmt(t, 3));
  }
  el("rect", { x: x0, y: y0, width: w, height: h, fill: "none", stroke: "#888" }, g);
  if (opts.xlabel) el("text", { x: x0 + w / 2, y: y0 + h + 28, "text-anchor": "middle" }, g, opts.xlabel);
  if (opts.ylabel) el("text", { x: x0 - 38, y: y0 + h / 2, "text-anchor": "middle", transform: `rotate(-90 ${x0 - 38} ${y0 + h / 2})` }, g, opts.ylabel);
  const inner = el("g", { "clip-path": `url(#${clipId})` }, g);
  return { g: inner, outer: g, fx, fy };
}

function line(ax, xs, ys, attrs) {
  let d = "", pen = false;
  for (let i = 0; i < xs.length; i++) {
    if (ys[i] === null || ys[i] === undefined || !isFinite(ys[i])) { pen = false; continue; }
    d += (pen ? "L" : "M") + ax.fx(xs[i]).toFixed(1) + "," + ax.fy(ys[i]).toFixed(1);
    pen = true;
  }
  if (d) el("path", { d, fill: "none", "stroke-width": 1.6, ...attrs }, ax.g);
}

function band(ax, xs, lo, hi, colour) {
  // one polygon per run of points where both ends are finite
  let run = [];
  const flush = () => {
    if (run.length > 1) {
      const top = run.map((i) => `${ax.fx(xs[i]).toFixed(1)},${ax.fy(hi[i]).toFixed(1)}`);
      const bottom = run.slice().reverse().map((i) => `${ax.fx(xs[i]).toFixed(1)},${ax.fy(lo[i]).toFixed(1)}`);
      el("polygon", { points: top.concat(bottom).join(" "), fill: colour, opacity: 0.22, stroke: "none" }, ax.g);
    }
    run = [];
  };
  for (let i = 0; i < xs.length; i++) {
    if ([lo[i], hi[i]].every((v) => v !== null && isFinite(v))) run.push(i); else flush();
  }
  flush();
}

function legend(svg, x, y, items) {
  items.forEach(([label, colour, dash], k) => {
    el("line", { x1: x, x2: x + 18, y1: y + 14 * k, y2: y + 14 * k, stroke: colour, "stroke-width": 2, "stroke-dasharray": dash || "" }, svg);
    el("text", { x: x + 22, y: y + 14 * k + 4 }, svg, label);
  });
}

function clear(svg) { while (svg.firstChild) svg.removeChild(svg.firstChild); }

function drawEigen(e, u) {
  const svg = $("fig-eigen"); clear(svg);
  const v = e.speeds;
  let lo = Infinity, hi = -Infinity;
  e.real.forEach((row) => row.forEach((x) => { if (x !== null) { lo = Math.min(lo, x); hi = Math.max(hi, x); } }));
  e.imag.forEach((row) => row.forEach((x) => { if (x !== null) hi = Math.max(hi, Math.abs(x)); }));
  lo = Math.max(lo, -10); hi = Math.min(Math.max(hi, 1), 10);
  const ax = axes(svg, [55, 12, 420, 300], [0, 10], [lo, hi], { xlabel: "speed v [m/s]", ylabel: "eigenvalue [1/s]" });
  for (const [a, b] of e.stable_intervals) {
    const right = b === null ? 10 : Math.min(b, 10);
    el("rect", { x: ax.fx(a), y: 12, width: Math.max(0, ax.fx(right) - ax.fx(a)), height: 300, fill: "#9e9e9e", opacity: 0.18 }, ax.g);
  }
  if (u && u.band) {
    for (const [name, b] of Object.entries(u.band)) {
      const plus = (a, s) => a.map((x, i) => (x === null || s[i] === null ? null : x + s[i]));
      const minus = (a, s) => a.map((x, i) => (x === null || s[i] === null ? null : x - s[i]));
      band(ax, v, minus(b.real, b.sigma_real), plus(b.real, b.sigma_real), COLOURS[name]);
      if (name === "weave") band(ax, v, minus(b.imag, b.sigma_imag), plus(b.imag, b.sigma_imag), COLOURS[name]);
    }
  }
  e.names.forEach((name, k) => {
    const colour = COLOURS[name] || COLOURS.other;
    line(ax, v, e.real.map((r) => r[k]), { stroke: colour });
    if (name === "weave" && k === e.names.indexOf("weave")) {
      line(ax, v, e.imag.map((r) => (r[k] === null ? null : Math.abs(r[k]))), { stroke: colour, "stroke-dasharray": "5 3" });
    }
  });
  for (const [key, colour] of [["weave", COLOURS.weave], ["capsize", COLOURS.capsize]]) {
    if (e[key] !== null && e[key] <= 10) el("line", { x1: ax.fx(e[key]), x2: ax.fx(e[key]), y1: 12, y2: 312, stroke: colour, "stroke-dasharray": "2 3" }, ax.g);
  }
  legend(svg, 490, 24, [["weave (real)", COLOURS.weave], ["weave |imag|", COLOURS.weave, "5 3"], ["capsize", COLOURS.capsize],
    ["castor", COLOURS.castor], ["other", COLOURS.other]]);
  el("rect", { x: 490, y: 96, width: 18, height: 10, fill: "#9e9e9e", opacity: 0.35 }, svg);
  el("text", { x: 512, y: 105 }, svg, "self-stable");
  el("rect", { x: 490, y: 112, width: 18, height: 10, fill: COLOURS.weave, opacity: 0.3 }, svg);
  el("text", { x: 512, y: 121 }, svg, "one sigma (first order)");
}

// The speeds with their sigmas: first order at once, the Monte Carlo sigmas (mc) once edits pause.
function drawSpeeds(e, u, mc) {
  const first = (u && u.speeds) || {}, sampled = (mc && mc.speeds) || {};
  const one = (key) => {
    if (e[key] === null) return `${key}: none`;
    if (!mc) return `${key} ${fmt(e[key], 4)} +/- ${fmt(first[key], 2)} m/s (first order; Monte Carlo follows)`;
    const m = sampled[key] || {};
    return `${key} ${fmt(e[key], 4)} +/- ${fmt(m.monte_carlo, 2)} m/s (first order +/- ${fmt(m.first_order, 2)})`;
  };
  const intervals = e.stable_intervals.map(([a, b]) => `${fmt(a, 3)}-${b === null ? "inf" : fmt(b, 3)}`).join(", ") || "none";
  $("speeds").textContent = `${one("weave")};  ${one("capsize")};  self-stable ${intervals} m/s` +
    (mc ? `;  sigmas: Monte Carlo, ${mc.samples} draws` : "");
}

// The Monte Carlo sigmas of the latest valid table, asked for once no edit came for a while.
const MONTE_CARLO_PAUSE_MS = 400;
function scheduleMonteCarlo(data) {
  clearTimeout(state.mcTimer);
  const sequence = state.sequence;
  state.mcTimer = setTimeout(async () => {
    if (state.busy || state.pending || sequence !== state.sequence) return;
    try {
      const reply = await api("/api/monte_carlo", { cells: data.cells });
      if (sequence === state.sequence && reply.ok) {
        state.mcDone += 1;
        drawSpeeds(data.eigenvalues, data.uncertainty, reply.monte_carlo);
      }
    } catch (err) {
      $("status").textContent = `error: ${err.message}`;
    }
  }, MONTE_CARLO_PAUSE_MS);
}

function drawSide(s) {
  const svg = $("fig-side"); clear(svg);
  const top = Math.max(-s.bodies.H.y, s.bodies.B.y, 2 * s.rF, 1.2) + 0.2;
  const xlo = -s.rR - 0.1, xhi = s.w + s.rF + 0.25;
  const h = 270, w = Math.min(440, h * (xhi - xlo) / top);
  const ax = axes(svg, [45, 8, w, h], [xlo, xhi], [0, top], { xlabel: "x [m]", ylabel: "height [m]" });
  const scale = (ax.fx(1) - ax.fx(0));
  el("circle", { cx: ax.fx(0), cy: ax.fy(s.rR), r: s.rR * scale, fill: "none", stroke: "#444", "stroke-width": 1.5 }, ax.g);
  el("circle", { cx: ax.fx(s.w), cy: ax.fy(s.rF), r: s.rF * scale, fill: "none", stroke: "#444", "stroke-width": 1.5 }, ax.g);
  const up = [-Math.sin(s.lam), Math.cos(s.lam)], ground = [s.w + s.c, 0];
  const len = top / up[1];
  el("line", { x1: ax.fx(ground[0]), y1: ax.fy(0), x2: ax.fx(ground[0] + len * up[0]), y2: ax.fy(len * up[1]), stroke: "#777", "stroke-dasharray": "6 3" }, ax.g);
  for (const body of ["B", "H"]) {
    const e = s.ellipses[body], b = s.bodies[body];
    el("ellipse", { cx: ax.fx(b.x), cy: ax.fy(b.y), rx: e.a * scale, ry: e.b * scale, fill: BODY[body], opacity: 0.15, stroke: BODY[body],
      transform: `rotate(${-e.angle * 180 / Math.PI} ${ax.fx(b.x)} ${ax.fy(b.y)})` }, ax.g);
  }
  for (const [body, b] of Object.entries(s.bodies)) {
    el("circle", { cx: ax.fx(b.x), cy: ax.fy(b.y), r: body === "T" ? 7 : 5, fill: BODY[body], stroke: "#fff", "stroke-width": 1 }, ax.g);
    el("text", { x: ax.fx(b.x) + 8, y: ax.fy(b.y) - 6 }, ax.g, `${body} ${fmt(b.mass, 3)} kg`);
  }
  el("text", { x: 45 + w + 8, y: 24 }, svg, "centres of mass: R, B, H, F; T whole");
  el("text", { x: 45 + w + 8, y: 40 }, svg, "ellipses: inertia of B and H");
}

function drawModes(e, speed) {
  const svg = $("fig-modes"); clear(svg);
  const i = Math.round(speed * 10);
  el("text", { x: 10, y: 16 }, svg, `v = ${speed.toFixed(1)} m/s: |roll| and |steer| of each mode's eigenvector (they square-sum to 1), steer phase from roll`);
  e.names.forEach((name, k) => {
    const x = 20 + k * 155, colour = COLOURS[name] || COLOURS.other;
    const lam = e.real[i][k], im = e.imag[i][k];
    el("text", { x, y: 40 }, svg, `${name}: ${fmt(lam, 3)}${im ? (im > 0 ? " + " : " - ") + fmt(Math.abs(im), 3) + "i" : ""}`);
    const roll = e.roll[i][k], steer = e.steer[i][k];
    el("rect", { x, y: 50, width: 120 * roll, height: 16, fill: colour, opacity: 0.8 }, svg);
    el("text", { x: x + 2, y: 80 }, svg, `roll ${fmt(roll, 3)}`);
    el("rect", { x, y: 88, width: 120 * steer, height: 16, fill: colour, opacity: 0.45 }, svg);
    el("text", { x: x + 2, y: 118 }, svg, `steer ${fmt(steer, 3)}`);
    el("text", { x: x + 2, y: 140 }, svg, `phase ${fmt(e.steer_phase_deg[i][k], 3)} deg`);
  });
}

function drawBode(b) {
  const svg = $("fig-bode"); clear(svg);
  const f = b.frequencies;
  const all = (key) => [].concat(b.phi[key], b.delta[key]).filter((x) => x !== null && isFinite(x));
  const m = all("magnitude_db"), p = all("phase_deg");
  const top = axes(svg, [55, 10, 420, 140], [f[0], f[f.length - 1]], [Math.min(...m) - 5, Math.max(...m) + 5], { logx: true, ylabel: "magnitude [dB]" });
  const bottom = axes(svg, [55, 180, 420, 140], [f[0], f[f.length - 1]], [Math.min(...p) - 10, Math.max(...p) + 10], { logx: true, xlabel: "frequency [rad/s]", ylabel: "phase [deg]" });
  line(top, f, b.phi.magnitude_db, { stroke: "#1f77b4" });
  line(top, f, b.delta.magnitude_db, { stroke: "#ff7f0e" });
  line(bottom, f, b.phi.phase_deg, { stroke: "#1f77b4" });
  line(bottom, f, b.delta.phase_deg, { stroke: "#ff7f0e" });
  legend(svg, 490, 24, [["roll angle / steer torque", "#1f77b4"], ["steer angle / steer torque", "#ff7f0e"]]);
  el("text", { x: 490, y: 64 }, svg, `v = ${b.speed.toFixed(1)} m/s`);
}

function viridis(t) {
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const k = Math.min(stops.length - 2, Math.floor(t)), a = t - k;
  const c = stops[k].map((x, j) => Math.round(x + a * (stops[k + 1][j] - x)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function drawMap(m) {
  const svg = $("fig-map"); clear(svg);
  if (!m) { el("text", { x: 20, y: 30 }, svg, "choose a parameter for the map"); return; }
  const xs = m.values[0];
  const dx = (xs[1] - xs[0]) / 2;
  if (m.names.length === 1) {
    const ax = axes(svg, [55, 10, 420, 300], [xs[0] - dx, xs[xs.length - 1] + dx], [0, 10], { xlabel: m.names[0], ylabel: "speed [m/s]" });
    xs.forEach((x, i) => {
      if (!m.valid[i]) { el("rect", { x: ax.fx(x - dx), y: 10, width: ax.fx(x + dx) - ax.fx(x - dx), height: 300, fill: "#ccc" }, ax.g); return; }
      m.lower[i].forEach((lo, k) => {
        if (lo === null) return;
        const hi = m.upper[i][k] === null ? 10 : Math.min(m.upper[i][k], 10);
        el("rect", { x: ax.fx(x - dx), y: ax.fy(hi), width: ax.fx(x + dx) - ax.fx(x - dx) + 0.5, height: Math.max(0, ax.fy(lo) - ax.fy(hi)), fill: "#2ca02c", opacity: 0.55 }, ax.g);
      });
    });
    el("line", { x1: ax.fx(m.base[0]), x2: ax.fx(m.base[0]), y1: 10, y2: 310, stroke: "#000", "stroke-dasharray": "4 3" }, ax.g);
    legend(svg, 490, 24, [["self-stable speeds", "#2ca02c"], ["this bicycle", "#000", "4 3"], ["impossible design", "#ccc"]]);
    return;
  }
  const ys = m.values[1], dy = (ys[1] - ys[0]) / 2;
  const ax = axes(svg, [55, 10, 420, 300], [xs[0] - dx, xs[xs.length - 1] + dx], [ys[0] - dy, ys[ys.length - 1] + dy], { xlabel: m.names[0], ylabel: m.names[1] });
  xs.forEach((x, i) => ys.forEach((y, j) => {
    const lo = m.lower[i][j];
    const fill = !m.valid[i][j] ? "#ccc" : lo === null ? "#fff" : viridis(lo / 10);
    el("rect", { x: ax.fx(x - dx), y: ax.fy(y + dy), width: ax.fx(x + dx) - ax.fx(x - dx) + 0.5, height: ax.fy(y - dy) - ax.fy(y + dy) + 0.5, fill }, ax.g);
  }));
  el("circle", { cx: ax.fx(m.base[0]), cy: ax.fy(m.base[1]), r: 5, fill: "#fff", stroke: "#000" }, ax.g);
  for (let k = 0; k <= 5; k++) {
    el("rect", { x: 495, y: 30 + k * 18, width: 16, height: 16, fill: viridis(k / 5) }, svg);
    el("text", { x: 515, y: 42 + k * 18 }, svg, `${2 * k} m/s`);
  }
  el("text", { x: 490, y: 20 }, svg, "self-stable from (weave)");
  el("rect", { x: 495, y: 144, width: 16, height: 16, fill: "#fff", stroke: "#888" }, svg);
  el("text", { x: 515, y: 156 }, svg, "never self-stable");
  el("rect", { x: 495, y: 164, width: 16, height: 16, fill: "#ccc" }, svg);
  el("text", { x: 515, y: 176 }, svg, "impossible design");
  el("circle", { cx: 503, cy: 192, r: 5, fill: "#fff", stroke: "#000" }, svg);
  el("text", { x: 515, y: 196 }, svg, "this bicycle");
}

function drawLoop(c) {
  const svg = $("fig-loop"); clear(svg);
  if (!c) { $("loop-speeds").textContent = ""; el("text", { x: 20, y: 30 }, svg, "give gains and Apply: the closed loop's eigenvalues against speed"); return; }
  const v = c.speeds;
  let lo = Infinity, hi = -Infinity;
  c.real.forEach((row) => row.forEach((x) => { if (x !== null) { lo = Math.min(lo, x); hi = Math.max(hi, x); } }));
  c.imag.forEach((row) => row.forEach((x) => { if (x !== null) hi = Math.max(hi, Math.abs(x)); }));
  lo = Math.max(lo, -10); hi = Math.min(Math.max(hi, 1), 10);
  const ax = axes(svg, [55, 12, 420, 300], [0, 10], [lo, hi], { xlabel: "speed v [m/s]", ylabel: "eigenvalue [1/s]" });
  for (const [a, b] of c.stable_intervals) {
    const right = b === null ? 10 : Math.min(b, 10);
    if (a < 10) el("rect", { x: ax.fx(a), y: 12, width: Math.max(0, ax.fx(right) - ax.fx(a)), height: 300, fill: "#9e9e9e", opacity: 0.18 }, ax.g);
  }
  v.forEach((speed, i) => c.labels[i].forEach((label, k) => {
    const colour = COLOURS[label] || COLOURS.other;
    if (c.real[i][k] !== null) el("circle", { cx: ax.fx(speed), cy: ax.fy(c.real[i][k]), r: 1.6, fill: colour }, ax.g);
    if (c.imag[i][k] !== null && c.imag[i][k] > 0) el("circle", { cx: ax.fx(speed), cy: ax.fy(c.imag[i][k]), r: 1.6, fill: "none", stroke: colour }, ax.g);
  }));
  legend(svg, 490, 24, [["weave", COLOURS.weave], ["capsize", COLOURS.capsize], ["castor", COLOURS.castor], ["other", COLOURS.other]]);
  el("text", { x: 490, y: 90 }, svg, "filled: real part; open: imaginary");
  el("rect", { x: 490, y: 100, width: 18, height: 10, fill: "#9e9e9e", opacity: 0.35 }, svg);
  el("text", { x: 512, y: 109 }, svg, "stable");
  const intervals = c.stable_intervals.map(([a, b]) => `${fmt(a, 3)}-${b === null ? "inf" : fmt(b, 3)}`).join(", ") || "none";
  $("loop-speeds").textContent = `closed loop stable ${intervals} m/s`;
}

// ---------------------------------------------------------------- the table
function buildTable(table) {
  const body = $("params").tBodies[0];
  body.innerHTML = "";
  let group = null;
  for (const row of table.rows) {
    if (row.group !== group) {
      group = row.group;
      const tr = html("tr", { class: "group" }, body);
      html("td", { colspan: 4 }, tr, group);
    }
    const tr = html("tr", { "data-name": row.name }, body);
    html("td", {}, tr, row.name);
    for (const [k, label] of [[0, "value"], [1, "sigma"]]) {
      const td = html("td", {}, tr);
      const input = html("input", { "data-name": row.name, "data-k": k, "aria-label": `${row.name} ${label}` }, td);
      input.addEventListener("change", onEdit);
    }
    html("td", {}, tr, row.unit);
  }
  html("tr", { "data-name": "*" }, body);
}

// The table's values (unless being typed in) and its messages, without rebuilding it: focus stays.
function refreshTable(errors, editNotes) {
  const notes = { ...(state.loadNotes || {}) };  // the readers' notes stay next to their values
  for (const [k, list] of Object.entries(editNotes || {})) notes[k] = (notes[k] || []).concat(list);
  const body = $("params").tBodies[0];
  for (const input of body.querySelectorAll("input[data-name]")) {
    const cell = state.cells[input.dataset.name];
    const value = cell ? cell[Number(input.dataset.k)] : null;
    if (document.activeElement !== input) input.value = value === null || value === undefined ? "" : String(value);
  }
  for (const old of document.querySelectorAll("#params tr.message, #steer tr.message")) old.remove();
  for (const tr of document.querySelectorAll("#params tr[data-name], #steer tr[data-name]")) {
    const name = tr.dataset.name;
    tr.classList.toggle("bad", !!(errors || {})[name]);
    let after = tr;
    for (const [list, cls] of [[(errors || {})[name], "error"], [(notes || {})[name], "note"]]) {
      for (const message of list || []) {
        const m = html("tr", { class: "message", "data-for": name });
        html("td", { colspan: 4, class: cls }, m, message);
        after.after(m);
        after = m;
      }
    }
  }
}

function buildSteer(table) {
  const body = $("steer").tBodies[0];
  if (!body.rows.length) {
    for (const row of table.steer_frame) {
      const tr = html("tr", { "data-name": row.name }, body);
      html("td", {}, tr, row.name);
      const input = html("input", { "data-steer": row.name, "aria-label": `${row.name} value` }, html("td", {}, tr));
      input.addEventListener("change", onSteerEdit);
      html("td", { "data-sigma": row.name }, tr);
      html("td", {}, tr, row.unit);
    }
  }
  for (const row of table.steer_frame) {
    const input = body.querySelector(`input[data-steer="${row.name}"]`);
    if (document.activeElement !== input) input.value = String(row.value);
    body.querySelector(`td[data-sigma="${row.name}"]`).textContent = fmt(row.sigma, 3);
  }
  const a = table.assembly;
  const principal = (b) => {
    const p = table.principal[b];
    return `${b}: ${fmt(p.plane[0], 4)}, ${fmt(p.plane[1], 4)} in the xz plane (first axis ${fmt(p.angle * 180 / Math.PI, 3)} deg from x)` +
      (p.yy === null ? "" : `, Iyy ${fmt(p.yy, 4)}`);
  };
  $("assembly").textContent = `Front assembly H + F: mass ${fmt(a.mass, 4)} +/- ${fmt(a.mass_sigma, 2)} kg, ` +
    `moment of inertia about the steer axis ${fmt(a.I_steer_axis, 4)} +/- ${fmt(a.I_steer_axis_sigma, 2)} kg m^2 (first order). ` +
    `Principal moments [kg m^2] of ${principal("B")}; of ${principal("H")}.`;
}

function onEdit(event) {
  const input = event.target;
  const name = input.dataset.name, k = Number(input.dataset.k);
  state.cells[name][k] = input.value;
  state.steerEdit = null;
  requestUpdate();
}

function onSteerEdit() {
  state.steerEdit = {};
  for (const input of document.querySelectorAll("input[data-steer]")) state.steerEdit[input.dataset.steer] = input.value;
  requestUpdate();
}

// ---------------------------------------------------------------- updates: one request per change, latest wins
function requestUpdate() {
  state.pending = { t0: performance.now(), body: { cells: state.cells, steer_frame: state.steerEdit, speed: state.speed, map: mapSpec(), gains: state.gains } };
  if (!state.busy) sendUpdate();
}

async function sendUpdate() {
  const job = state.pending;
  state.pending = null;
  state.busy = true;
  try {
    const data = await api("/api/update", job.body);
    const t1 = performance.now();
    render(data);
    const t2 = performance.now();
    await new Promise((resolve) => requestAnimationFrame(() => resolve()));
    const ms = performance.now() - job.t0;
    state.latencies.push(ms);
    state.breakdown.push({ request: t1 - job.t0, draw: t2 - t1, paint: performance.now() - t2, server: data.timing });
    $("status").textContent = data.ok ? `updated in ${ms.toFixed(0)} ms` : "the table has errors: figures show the last valid bicycle";
  } catch (err) {
    $("status").textContent = `error: ${err.message}`;
    $("table-errors").textContent = err.message;
  } finally {
    state.busy = false;
    if (state.pending) sendUpdate();
  }
}

function render(data) {
  $("table-errors").textContent = "";
  if (!data.ok) {
    refreshTable(data.errors, data.notes);
    return;
  }
  state.cells = data.cells;
  state.steerEdit = null;
  state.last = data;
  refreshTable(data.errors, data.notes);
  buildSteer(data.table);
  drawEigen(data.eigenvalues, data.uncertainty);
  state.sequence += 1;
  drawSpeeds(data.eigenvalues, data.uncertainty, null);
  scheduleMonteCarlo(data);
  drawSide(data.side_view);
  drawModes(data.eigenvalues, data.speed);
  drawBode(data.bode);
  $("map-error").textContent = data.map_error || "";
  drawMap(data.map);
  $("loop-error").textContent = data.gains_error || "";
  drawLoop(data.closed_loop);
  if (data.map_axes) {
    const [x, y] = data.map_axes;
    $("map-x-lo").value = fmt(x[1], 4); $("map-x-hi").value = fmt(x[2], 4);
    if (y) { $("map-y-lo").value = fmt(y[1], 4); $("map-y-hi").value = fmt(y[2], 4); }
  }
}

function mapSpec() {
  const spec = { x: state.map.x, y: state.map.y };
  if (state.map.xRange) spec.x_range = state.map.xRange;
  if (state.map.y && state.map.yRange) spec.y_range = state.map.yRange;
  return spec;
}

// ---------------------------------------------------------------- loading a bicycle
function loaded(data) {
  $("load-error").textContent = "";
  $("bicycle-name").textContent = data.name;
  state.name = data.name;
  const notes = $("load-notes"); notes.innerHTML = "";
  for (const n of data.notes) html("li", {}, notes, n);
  state.cells = data.cells;
  state.loadNotes = data.note_fields;
  delete state.loadNotes["*"];  // listed under the bicycle's name
  state.steerEdit = null;
  state.map.xRange = state.map.yRange = null;
  buildTable(data.table);
  refreshTable({}, {});
  requestUpdate();
}

async function uploadFiles(kind, files) {
  for (const { file, name } of files) {  // the server's limits, said before anything is sent
    const limit = (state.limits || {})[kind];
    if (limit && file.size > limit) throw new Error(`${name} = '${file.size} bytes': expected an uploaded ${kind} file of at most ${limit} bytes`);
  }
  const { folder } = await api("/api/upload/new", { kind });
  let listing = [];
  for (const { file, name } of files) {
    const response = await fetch(`/api/upload/${folder}?name=${encodeURIComponent(name)}`, { method: "PUT", body: file });
    const data = await response.json();
    if (!response.ok) throw new Error(data.error);
    listing = data.files;
  }
  return { folder, files: listing };
}

async function loadFiles() {
  const bike = $("bicycle-file").files[0], rider = $("rider-file").files[0];
  if (!bike) { $("load-error").textContent = "choose a bicycle file first"; return; }
  try {
    const files = [{ file: bike, name: bike.name }];
    if (rider) files.push({ file: rider, name: rider.name === bike.name ? "rider-" + rider.name : rider.name });
    const { folder } = await uploadFiles("bicycle", files);
    loaded(await api("/api/bicycle/files", { folder, bicycle: files[0].name, rider: rider ? files[1].name : null }));
  } catch (err) {
    $("load-error").textContent = `error: ${err.message}`;
  }
}

// ---------------------------------------------------------------- downloads
async function download(body) {
  $("download-status").textContent = "preparing...";
  try {
    const response = await fetch("/api/download", { method: "POST", headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ cells: state.cells, speed: state.speed, map: mapSpec(), name: state.name, ...body }) });
    if (!response.ok) throw new Error((await response.json()).error);
    const blob = await response.blob();
    const name = (response.headers.get("Content-Disposition") || "").match(/filename="([^"]+)"/)[1];
    const a = html("a", { href: URL.createObjectURL(blob), download: name }, document.body);
    a.click();
    a.remove();
    $("download-status").textContent = `downloaded ${name}`;
  } catch (err) {
    $("download-status").textContent = `error: ${err.message}`;
  }
}

// ---------------------------------------------------------------- the gap
async function gapUpload(list) {
  $("gap-error").textContent = "";
  const files = Array.from(list).map((file) => ({ file, name: (file.webkitRelativePath || file.name).split("/").slice(file.webkitRelativePath ? 1 : 0).join("/") }));
  if (!files.length) return;
  $("gap-upload-status").textContent = `uploading ${files.length} files...`;
  try {
    const { folder, files: listing } = await uploadFiles("experiment", files);
    state.gapFolder = folder;
    $("gap-upload-status").textContent = `uploaded: ${listing.join(", ")}`;
    const fill = (select, guess) => {
      select.innerHTML = "";
      for (const name of listing) {
        const option = html("option", { value: name }, select, name);
        if (guess(name)) option.selected = true;
      }
    };
    const model = listing.find((n) => /\.toml$/.test(n) && /(bicycle|model)/i.test(n)) || listing.find((n) => /Benchmark\.txt$/.test(n));
    fill($("gap-model"), (n) => n === model);
    fill($("gap-experiment"), (n) => /\.toml$/.test(n) && /(experiment|manifest)/i.test(n));
    fill($("gap-data"), () => false);
  } catch (err) {
    $("gap-error").textContent = `error: ${err.message}`;
    $("gap-upload-status").textContent = "";
  }
}

async function gapRun() {
  $("gap-error").textContent = "";
  for (const id of ["gap-summary", "gap-next-text", "gap-zip", "gap-figures"]) $(id).textContent = "";
  if (!state.gapFolder) { $("gap-error").textContent = "upload the experiment's files first"; return; }
  const chosen = (id) => Array.from($(id).selectedOptions).map((o) => o.value);
  try {
    const job = await api("/api/gap/run", { folder: state.gapFolder, model: $("gap-model").value, experiment: chosen("gap-experiment"),
      data: chosen("gap-data"), next: $("gap-next").checked });
    state.gapJob = job.id;
    pollGap();
  } catch (err) {
    $("gap-error").textContent = `error: ${err.message}`;
  }
}

async function pollGap() {
  let job;
  try { job = await api(`/api/gap/${state.gapJob}`); } catch (err) { $("gap-error").textContent = `error: ${err.message}`; return; }
  const at = job.step === "done" ? job.steps.length : job.step_index;
  const bar = at === null ? "" : job.steps.map((s, k) => (k < at ? "[x] " : k === at ? "[>] " : "[ ] ") + s).join("\n");
  $("gap-progress").textContent = `${job.step} (${job.elapsed === null ? 0 : job.elapsed} s)\n${bar}\n${job.messages.slice(-5).join("\n")}`;
  if (job.step === "failed") { $("gap-error").textContent = job.error; return; }
  if (job.step !== "done") { setTimeout(pollGap, 1000); return; }
  $("gap-summary").textContent = job.summary;
  $("gap-next-text").textContent = job.next || "";
  const zip = html("a", { href: `/api/gap/${job.id}/report.zip`, download: "gap_report.zip", id: "gap-zip-link" }, $("gap-zip"), "Download the report folder (zip)");
  zip.textContent = "Download the report folder (report.md and figures, zip)";
  for (const f of job.figures) {
    html("h3", {}, $("gap-figures"), f.caption);
    html("img", { src: `/api/gap/${job.id}/figure/${encodeURIComponent(f.name)}`, alt: f.caption }, $("gap-figures"));
  }
}

// ---------------------------------------------------------------- start
async function start() {
  const info = await api("/api/bicycles");
  state.limits = info.limits;
  for (const choice of info.shipped) html("option", { value: choice.id }, $("shipped"), choice.label);
  const names = ["w", "c", "lam", "rR", "mR", "IRxx", "IRyy", "xB", "zB", "mB", "IBxx", "IBzz", "IBxz", "xH", "zH", "mH", "IHxx", "IHzz", "IHxz", "rF", "mF", "IFxx", "IFyy"];
  html("option", { value: "" }, $("map-y"), "(none: one parameter)");
  for (const n of names) { html("option", { value: n }, $("map-x"), n); html("option", { value: n }, $("map-y"), n); }
  $("map-x").value = state.map.x;
  $("load-shipped").addEventListener("click", async () => {
    try { loaded(await api("/api/bicycle/shipped", { id: $("shipped").value })); } catch (err) { $("load-error").textContent = `error: ${err.message}`; }
  });
  $("load-files").addEventListener("click", loadFiles);
  $("speed").addEventListener("input", () => {
    state.speed = Number($("speed").value);
    $("speed-out").textContent = `${state.speed.toFixed(1)} m/s`;
    requestUpdate();
  });
  const changeAxis = () => {
    state.map = { x: $("map-x").value, y: $("map-y").value, xRange: null, yRange: null };
    requestUpdate();
  };
  $("map-x").addEventListener("change", changeAxis);
  $("map-y").addEventListener("change", changeAxis);
  $("map-apply").addEventListener("click", () => {
    state.map.xRange = [$("map-x-lo").value, $("map-x-hi").value];
    state.map.yRange = state.map.y ? [$("map-y-lo").value, $("map-y-hi").value] : null;
    requestUpdate();
  });
  for (const button of document.querySelectorAll("#downloads button[data-kind]")) {
    button.addEventListener("click", () => download({ kind: button.dataset.kind, format: button.dataset.format }));
  }
  $("dl-figure-go").addEventListener("click", () => download({ kind: $("dl-figure").value, format: $("dl-format").value }));
  $("loop-apply").addEventListener("click", () => {
    state.gains = {};
    for (const k of ["k_phi", "k_phid", "k_delta", "k_deltad"]) state.gains[k] = $(k).value;
    requestUpdate();
  });
  $("loop-off").addEventListener("click", () => { state.gains = null; requestUpdate(); });
  $("gap-folder").addEventListener("change", (e) => gapUpload(e.target.files));
  $("gap-files").addEventListener("change", (e) => gapUpload(e.target.files));
  $("gap-run").addEventListener("click", gapRun);
  $("shipped").value = "Browser+Jason";
  loaded(await api("/api/bicycle/shipped", { id: "Browser+Jason" }));
}

document.addEventListener("DOMContentLoaded", () => start().catch((err) => { $("status").textContent = `error: ${err.message}`; }));
