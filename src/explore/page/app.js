// kardia explore: the page. Plain JavaScript, no dependencies. Every view is sent to the
// server as a whole scene text (the text is the one truth: "Copy scene" is exactly what was
// rendered); frames come back as raw RGBA and are drawn on the canvas.
"use strict";

const $ = (id) => document.getElementById(id);
const canvas = $("view");
const ctx = canvas.getContext("2d");

const DEFAULT_CAMERA = { eye: [6, 1.2, 0.9], look: [0, 0, 0.05], up: [0, 0, 1], fov: 32 };

const state = {
  mode: "equation",       // "equation" | "scene"
  presetId: "heart",      // gallery entry, or null for a typed equation
  params: [],             // the preset's parameters
  scale: 1,               // object-space scale of the placed surface
  equation: "",           // typed (or expanded) equation text
  bound: 2,
  boundAuto: true,        // a preset's clip radius follows its parameters (no BOUND written)
  letters: {},            // a typed equation's free letters: name -> {value, min, max}
  outside: "#e03050",
  inside: "#f0d060",
  sceneName: "",
  sceneText: "",
  camera: structuredClone(DEFAULT_CAMERA),
  homeCamera: structuredClone(DEFAULT_CAMERA),
  fixedSize: null,        // [w, h] from the URL, else the canvas follows the window
  view: "shaded",         // which image (a `kardia render --view` name)
};

let socket = null;
let hello = null;
let seq = 0;              // last view request sent
let drawnSeq = -1;        // request of the frame on the canvas
let lastText = "";
let pendingSave = null;
const stats = { firstInput: 0 };
// For tests and the measuring script: what the page received and sent.
window.kardia = {
  state, frames: [], views: [], errors: [], messages: [], saveProgress: [], meshProgress: [], problems: [], lastProblem: null, extent: null,
  sent: () => seq, currentScene: () => currentScene(),
};

// ---------- numbers and vectors ----------
const fmt = (v) => {
  const r = Number(v.toFixed(5));
  return Object.is(r, -0) ? "0" : String(r);
};
const vec = (v) => `(${v.map(fmt).join(", ")})`;
const add = (a, b) => a.map((x, i) => x + b[i]);
const sub = (a, b) => a.map((x, i) => x - b[i]);
const mul = (a, s) => a.map((x) => x * s);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const len = (a) => Math.sqrt(dot(a, a));
const unit = (a) => mul(a, 1 / (len(a) || 1));
// Rotates v about the unit axis k by angle a (Rodrigues).
const rotate = (v, k, a) => {
  const c = Math.cos(a), s = Math.sin(a);
  return add(add(mul(v, c), mul(cross(k, v), s)), mul(k, dot(k, v) * (1 - c)));
};
const srgbToLinear = (hex) => {
  const n = parseInt(hex.slice(1), 16);
  return [(n >> 16) & 255, (n >> 8) & 255, n & 255].map((c) => {
    const s = c / 255;
    return s <= 0.04045 ? s / 12.92 : Math.pow((s + 0.055) / 1.055, 2.4);
  });
};

// ---------- the scene text ----------
function cameraLine(c) {
  const size = c.orthographic ? `ORTHOGRAPHIC ${fmt(c.fov)}` : fmt(c.fov);
  return `CAMERA ${vec(c.eye)} ${vec(c.look)} ${vec(c.up)} ${size}`;
}

function isCameraLine(line) {
  return /^\s*camera\b/i.test(line.replace(/^\uFEFF/, ""));
}

// The camera written in a scene text, or null when its CAMERA line is not plain numbers.
function cameraFromText(text) {
  const line = text.split("\n").find(isCameraLine);
  if (!line) return null;
  const nums = (line.split("#")[0].match(/[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?/g) || []).map(Number);
  if (nums.length !== 10 || nums.some((n) => !Number.isFinite(n))) return null;
  const orthographic = /\borthographic\b/i.test(line.split("#")[0]);
  return { eye: nums.slice(0, 3), look: nums.slice(3, 6), up: nums.slice(6, 9), fov: nums[9], orthographic };
}

function withCamera(text, camera) {
  const lines = text.split("\n");
  const i = lines.findIndex(isCameraLine);
  const line = cameraLine(camera);
  // Appended, not inserted: the user's own lines keep their numbers.
  if (i < 0) return text + (text === "" || text.endsWith("\n") ? "" : "\n") + line + "\n";
  lines[i] = line + (lines[i].endsWith("\r") ? "\r" : "");
  return lines.join("\n");
}

// The free letters of a typed equation: single letters other than x, y, z (either case).
const LETTER = /[A-Za-z_][A-Za-z0-9_]*/g;
function freeLetters(equation) {
  const found = [];
  for (const m of equation.matchAll(LETTER)) {
    const name = m[0];
    if (name.length === 1 && !/[xyzXYZ]/.test(name) && !found.includes(name)) found.push(name);
  }
  return found;
}

// The typed equation with its free letters replaced by their values, and for every character
// of the result the index of the character of the typed text it came from.
function substituted(equation) {
  let out = "";
  const from = [];
  let last = 0;
  for (const m of equation.matchAll(LETTER)) {
    const name = m[0];
    const letter = state.letters[name];
    if (name.length !== 1 || !letter) continue;
    for (let i = last; i < m.index; i++) { out += equation[i]; from.push(i); }
    const value = `(${fmt(letter.value)})`;
    for (const ch of value) { out += ch; from.push(m.index); }
    last = m.index + name.length;
  }
  for (let i = last; i < equation.length; i++) { out += equation[i]; from.push(i); }
  from.push(equation.length);
  return { text: out.replace(/[\r\n"]/g, " "), from };
}

// Equation mode's scene; also records where the surface is written, to map errors back.
function equationScene() {
  const s = fmt(state.scale);
  const preset = state.presetId && presetById(state.presetId);
  let surface, from = null;
  if (preset && preset.preset) {
    surface = [preset.preset, ...state.params.map(fmt)].join(" ");
  } else {
    const sub = substituted(state.equation);
    surface = `"${sub.text}"`;
    from = sub.from;
  }
  const head = [
    "# kardia explore, equation mode",
    `SIZE ${saveSize().join(" ")}`,
    cameraLine(state.camera),
    "BACKGROUND (0.03, 0.03, 0.05)",
    "AMBIENT (0.06, 0.06, 0.07)",
    "LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 4",
    "LIGHT (3, 6, 1) (0.25, 0.25, 0.3)",
  ];
  const prefix = "IMPLICIT ";
  const bound = preset && preset.preset && state.boundAuto ? "" : ` BOUND ${fmt(state.bound)}`;
  const line = `${prefix}${surface} (0, 0, 0) (${s}, 0, 0) (0, ${s}, 0) (0, 0, ${s}) ` +
    `${vec(srgbToLinear(state.outside))} SPECULAR 0.4 60 INSIDE ${vec(srgbToLinear(state.inside))}` + bound;
  return {
    text: [...head, line, ""].join("\n"),
    surfaceLine: head.length + 1,
    // 1-based column of the equation's first character (after the quote).
    equationColumn: surface.startsWith('"') ? prefix.length + 2 : null,
    from,
  };
}

function currentScene() {
  if (state.mode === "equation") return equationScene().text;
  return withCamera(state.sceneText, state.camera);
}

const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

function saveSize() {
  const side = hello ? hello.limits.max_save_side : 8192;
  return [clamp(Math.round(Number($("save-width").value)) || 800, 1, side),
    clamp(Math.round(Number($("save-height").value)) || 600, 1, side)];
}

function saveSpp() {
  return clamp(Math.round(Number($("save-spp").value)) || 1, 1, hello ? hello.limits.max_save_spp : 1024);
}

// A view size within the server's limits (a side and the pixel count).
function clampViewSize([w, h]) {
  const side = hello ? hello.limits.max_view_side : 4096;
  const pixels = hello ? hello.limits.max_view_pixels : 2560 * 1600;
  w = clamp(Math.round(w), 16, side);
  h = clamp(Math.round(h), 16, side);
  if (w * h > pixels) {
    const k = Math.sqrt(pixels / (w * h));
    w = Math.floor(w * k);
    h = Math.floor(h * k);
  }
  return [w, h];
}

function viewSize() {
  if (state.fixedSize) return clampViewSize(state.fixedSize);
  const r = canvas.getBoundingClientRect();
  return clampViewSize([r.width, r.height]);
}

// ---------- talking to the server ----------
function connect() {
  socket = new WebSocket(`ws://${location.host}/ws`);
  socket.binaryType = "arraybuffer";
  socket.onmessage = (e) => (typeof e.data === "string" ? onText(JSON.parse(e.data)) : onBinary(e.data));
  socket.onclose = (e) => {
    setStatus(`disconnected from the server${e.reason ? " (" + e.reason + ")" : ""}: reload the page`, { error: true });
  };
}

function send(message) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}

// The status line: plain words, a progress bar, and the technical figures behind "details".
function setStatus(text, { error = false, progress = null, details = null } = {}) {
  $("status-text").textContent = text;
  $("status").classList.toggle("error", error);
  const bar = $("progress");
  if (progress === null) bar.removeAttribute("value");
  else bar.value = progress;
  if (details !== null) $("status-details").textContent = details;
}

// Shows a message under the controls (and keeps it for tests).
function say(text) {
  window.kardia.messages.push(text);
  $("message").textContent = text;
}

// Sends the current view (only when something changed).
let pendingTimer = null;
function update() {
  clearTimeout(pendingTimer);
  pendingTimer = null;
  if (!hello) return; // the URL's state is read once the server has said hello
  const text = currentScene();
  const [width, height] = viewSize();
  const key = `${width}x${height} ${state.view}\n${text}`;
  if (key === lastText) return;
  lastText = key;
  if (canvas.width !== width || canvas.height !== height) {
    // Keeps the picture while the new size renders.
    const old = document.createElement("canvas");
    old.width = canvas.width;
    old.height = canvas.height;
    old.getContext("2d").drawImage(canvas, 0, 0);
    canvas.width = width;
    canvas.height = height;
    ctx.drawImage(old, 0, 0, width, height);
  }
  seq += 1;
  stats.firstInput = performance.now();
  window.kardia.views.push({ seq, scene: text, at: performance.now() });
  if (window.kardia.views.length > 200) window.kardia.views.shift();
  send({ type: "view", seq, scene: text, width, height, view: state.view });
  writeUrl();
}

// Sends the view once nothing has changed for `ms` milliseconds (typing).
function updateSoon(ms = 150) {
  clearTimeout(pendingTimer);
  pendingTimer = setTimeout(update, ms);
}

// How long typed text must be still before it is drawn: 150 ms, or twice the typist's pace
// (the median interval of their last keystrokes, a second's stillness starting afresh) up to
// 600 ms, so someone typing at 5 characters a second does not see every half-typed equation.
const keystrokes = [];
function typingPause() {
  const now = performance.now();
  if (keystrokes.length && now - keystrokes[keystrokes.length - 1] >= 1000) keystrokes.length = 0;
  keystrokes.push(now);
  if (keystrokes.length > 7) keystrokes.shift();
  const gaps = keystrokes.slice(1).map((t, i) => t - keystrokes[i]).sort((a, b) => a - b);
  const pace = gaps.length ? gaps[Math.floor(gaps.length / 2)] : 0;
  window.kardia.typingPause = clamp(2 * pace, 150, 600);
  return window.kardia.typingPause;
}

function onText(m) {
  if (m.type === "hello") return onHello(m);
  if (m.type === "scene_error") return showProblem(m.seq, m.problem);
  if (m.type === "preset") return onPreset(m);
  if (m.type === "extent") return onExtent(m);
  if (m.type === "save_progress") return onSaveProgress(m);
  if (m.type === "probe") return onProbe(m);
  if (m.type === "mesh_progress") return onMeshProgress(m);
  if (m.type === "error") {
    window.kardia.errors.push(m.message);
    say(m.message);
    if (pendingSave && m.seq === pendingSave.seq) endSave();
    if (pendingMesh && m.seq === pendingMesh.seq) endMesh();
  }
}

function onBinary(buffer) {
  const view = new DataView(buffer);
  const n = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, n)));
  const payload = new Uint8Array(buffer, 4 + n);
  if (header.type === "png") return onPng(header, payload);
  if (header.type === "mesh") return onMesh(header, payload);
  if (header.seq < drawnSeq) return;
  if (header.seq > drawnSeq) {
    clearProblem();
    if (emptyFrom !== null && header.seq >= emptyFrom && state.mode === "equation") showNothingToDraw();
  }
  drawnSeq = header.seq;
  const image = new ImageData(new Uint8ClampedArray(payload.buffer, payload.byteOffset, payload.length),
    header.width, header.height);
  if (header.width === canvas.width && header.height === canvas.height) {
    ctx.putImageData(image, 0, 0);
  } else {
    const small = new OffscreenCanvas(header.width, header.height);
    small.getContext("2d").putImageData(image, 0, 0);
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(small, 0, 0, canvas.width, canvas.height);
  }
  if (header.seq === seq) canvas.classList.remove("stale");
  const ms = performance.now() - stats.firstInput;
  window.kardia.frames.push({ ...header, sinceInput: ms, receivedAt: performance.now() });
  if (window.kardia.frames.length > 1000) window.kardia.frames.shift();
  const full = header.width === header.view_width;
  const max = hello.limits.max_view_spp;
  const rate = header.ms > 0 ? header.rays / (header.ms / 1000) : 0;
  const details = `${header.width}×${header.height}` +
    (full ? "" : ` (of ${header.view_width}×${header.view_height})`) +
    ` · ${header.spp} spp · ${header.ms.toFixed(0)} ms/pass · ${(rate / 1e6).toFixed(2)} M rays/s`;
  const text = header.done ? `done: ${header.spp} samples a pixel`
    : full ? `refining: ${header.spp} / ${max} samples` : "drawing a quick preview…";
  setStatus(text, { progress: full ? header.spp : 0, details });
  $("progress").max = max;
}

function onHello(m) {
  hello = m;
  const gallery = $("gallery");
  gallery.innerHTML = "";
  for (const p of m.presets) {
    const b = document.createElement("button");
    b.dataset.preset = p.id;
    b.setAttribute("role", "listitem");
    b.setAttribute("aria-label", `${p.title}: ${p.about}`);
    b.title = p.about;
    const img = document.createElement("img");
    img.src = `thumbnail/${encodeURIComponent(p.id)}`;
    img.alt = "";
    img.loading = "lazy";
    const name = document.createElement("span");
    name.textContent = p.title;
    b.append(img, name);
    b.onclick = () => choosePreset(p.id);
    gallery.appendChild(b);
  }
  const select = $("scene-file");
  select.innerHTML = "";
  for (const [name] of m.scenes) {
    const o = document.createElement("option");
    o.value = o.textContent = name;
    select.appendChild(o);
  }
  const study = $("study");
  study.innerHTML = "";
  for (const name of m.views) {
    const o = document.createElement("option");
    o.value = o.textContent = name;
    study.appendChild(o);
  }
  legends = Object.fromEntries((m.legends || []).map((l) => [l.view, l]));
  openScene(m.initial[0], m.initial[1]);
  state.mode = m.start_mode === "scene" ? "scene" : "equation";
  applyUrl(false);
  history.replaceState(null, "", location.href);
  settled = location.hash;
}

// Applies the URL's state (whatever keys it has; the rest take defaults) and draws it.
function applyUrl(fromHistory) {
  const messages = readUrl();
  $("study").value = state.view;
  showLegend();
  if (state.mode === "equation") {
    if (state.presetId) choosePreset(state.presetId, { keepParams: true, keepView: true, fromUrl: true });
    else {
      const scale = state.scale;
      typedEquation(state.equation, { keepView: true });
      state.scale = state.scaleFromUrl ? scale : 1;
      if (!state.boundFromUrl) { state.boundAuto = false; state.bound = 2; }
      renderSliders();
    }
  }
  setMode(state.mode);
  if (messages.length) say(messages.join(" "));
  else if (fromHistory) say("");
}

function presetById(id) {
  return hello && hello.presets.find((p) => p.id === id);
}

// ---------- equation mode ----------
let equationReady = false; // equation mode has a surface
let frameNext = false;     // frame the next extent that arrives (a new equation)
function choosePreset(id, { keepParams = false, keepView = false, fromUrl = false } = {}) {
  equationReady = true;
  const p = presetById(id);
  if (!p) return choosePreset("heart");
  state.presetId = id;
  state.scale = fromUrl && state.scaleFromUrl ? state.scale : p.scale;
  if (!keepParams || state.params.length !== p.sliders.length) {
    state.params = p.sliders.map((s) => s.value);
  }
  state.params = state.params.map((v, i) => clamp(v, p.sliders[i].min, p.sliders[i].max));
  if (!fromUrl || !state.boundFromUrl) {
    state.bound = p.bound;
    state.boundAuto = Boolean(p.preset);
  }
  if (!keepView) {
    state.camera = structuredClone(DEFAULT_CAMERA);
    state.homeCamera = structuredClone(DEFAULT_CAMERA);
  }
  state.letters = {};
  frameNext = false;
  for (const b of document.querySelectorAll("#gallery button")) {
    b.classList.toggle("active", b.dataset.preset === id);
    b.setAttribute("aria-pressed", String(b.dataset.preset === id));
  }
  $("about").textContent = p.about;
  if (p.preset) {
    send({ type: "preset", name: p.preset, params: state.params });
  } else {
    state.equation = p.equation;
    $("equation").value = p.equation;
  }
  renderSliders();
  update();
}

// A typed equation becomes the surface (scale 1); its free letters get sliders.
function typedEquation(text, { keepView = false } = {}) {
  equationReady = true;
  const wasPreset = state.presetId !== null;
  state.presetId = null;
  state.equation = text;
  if (wasPreset) {
    state.scale = 1;
    state.boundAuto = false;
  }
  if (!keepView) frameNext = true;
  for (const b of document.querySelectorAll("#gallery button")) {
    b.classList.remove("active");
    b.setAttribute("aria-pressed", "false");
  }
  $("about").textContent = "";
  const names = freeLetters(text);
  for (const name of names) {
    if (!state.letters[name]) state.letters[name] = { value: 1, min: -2, max: 2 };
  }
  renderSliders();
}

function onPreset(m) {
  const p = state.presetId && presetById(state.presetId);
  if (!p || p.preset !== m.name || m.params.some((v, i) => v !== state.params[i])) return;
  state.equation = m.equation;
  $("equation").value = m.equation;
  if (state.boundAuto) {
    state.bound = m.bound;
    $("bound").value = m.bound;
    $("bound-value").textContent = fmt(m.bound);
  }
}

function slider({ id, label, min, max, step, value, onInput, bounds }) {
  const div = document.createElement("div");
  div.className = "slider";
  const lab = document.createElement("label");
  lab.htmlFor = id;
  const out = document.createElement("output");
  out.textContent = fmt(value);
  lab.append(`${label} `, out);
  const input = document.createElement("input");
  Object.assign(input, { type: "range", min, max, step, value });
  input.id = id;
  input.setAttribute("aria-label", label);
  input.oninput = () => {
    out.textContent = fmt(Number(input.value));
    onInput(Number(input.value));
  };
  div.append(lab, input);
  if (bounds) {
    const row = document.createElement("div");
    row.className = "bounds";
    for (const [which, v] of [["min", min], ["max", max]]) {
      const b = document.createElement("input");
      Object.assign(b, { type: "number", value: v, step: "any" });
      b.id = `${id}-${which}`;
      b.setAttribute("aria-label", `${label}: ${which === "min" ? "smallest" : "largest"} value`);
      b.onchange = () => bounds(which, Number(b.value));
      row.append(b);
    }
    div.append(row);
  }
  return div;
}

function renderSliders() {
  const box = $("sliders");
  box.replaceChildren();
  const p = state.presetId && presetById(state.presetId);
  if (p) {
    p.sliders.forEach((s, i) => {
      box.appendChild(slider({
        id: `param-${i}`, label: s.label, min: s.min, max: s.max, step: s.step, value: state.params[i],
        onInput: (v) => {
          state.params[i] = v;
          send({ type: "preset", name: p.preset, params: state.params });
          update();
        },
      }));
    });
  } else {
    for (const name of freeLetters(state.equation)) {
      const letter = state.letters[name];
      box.appendChild(slider({
        id: `letter-${name}`, label: name, min: letter.min, max: letter.max, step: "any", value: letter.value,
        onInput: (v) => { letter.value = v; update(); },
        bounds: (which, v) => {
          if (!Number.isFinite(v)) return renderSliders();
          letter[which] = v;
          if (letter.min > letter.max) [letter.min, letter.max] = [letter.max, letter.min];
          letter.value = clamp(letter.value, letter.min, letter.max);
          renderSliders();
          update();
        },
      }));
    }
  }
  $("bound").value = state.bound;
  $("bound-value").textContent = fmt(state.bound);
}

$("equation").addEventListener("input", () => {
  typedEquation($("equation").value);
  updateSoon(typingPause());
});
$("equation").addEventListener("keydown", (e) => {
  if (e.key === "Enter" && !e.shiftKey) {
    e.preventDefault();
    update();
  }
});
$("bound").addEventListener("input", () => {
  state.bound = Number($("bound").value);
  state.boundAuto = false;
  $("bound-value").textContent = fmt(state.bound);
  update();
});
for (const id of ["outside", "inside"]) {
  $(id).addEventListener("input", () => {
    state[id] = $(id).value;
    update();
  });
}

// ---------- framing ----------
// The request from which the surface has nothing to draw (its load-time extent, certified by
// the server, is empty: a box of no size), until an extent with something arrives.
let emptyFrom = null;
function onExtent(m) {
  if (m.seq !== seq) return;
  window.kardia.extent = { min: m.min, max: m.max };
  emptyFrom = len(sub(m.max, m.min)) / 2 > 1e-3 ? null : m.seq;
  if (frameNext && state.mode === "equation") {
    frameNext = false;
    fit();
  }
}

// Frames the last extent the server reported: the look-at point at its centre, the eye on
// the same side, far enough that its bounding sphere fills the narrower field of view.
function fit() {
  const e = window.kardia.extent;
  if (!e) return;
  const c = state.camera;
  const centre = mul(add(e.min, e.max), 0.5);
  const radius = len(sub(e.max, e.min)) / 2;
  // An empty or point-like surface (no real zeros, or a single point) is not framed.
  if (!(radius > 1e-3) || !centre.every(Number.isFinite)) return;
  const [w, h] = viewSize();
  const half = Math.min((c.fov * Math.PI) / 360, Math.atan(Math.tan((c.fov * Math.PI) / 360) * (h / w)));
  const distance = (radius / Math.sin(half)) * 1.02;
  const dir = unit(sub(c.eye, c.look));
  c.look = centre;
  c.eye = add(centre, mul(dir, distance));
  cameraChanged();
}
$("fit").onclick = () => fit();

// ---------- scene mode ----------
function openScene(name, text) {
  state.sceneName = name;
  state.sceneText = text;
  $("scene-text").value = text;
  showLineNumbers();
  const select = $("scene-file");
  if ([...select.options].some((o) => o.value === name)) select.value = name;
  const c = cameraFromText(text);
  if (c) {
    state.camera = c;
    state.homeCamera = structuredClone(c);
  }
}

function showLineNumbers(badLine = 0) {
  const count = $("scene-text").value.split("\n").length;
  const gutter = $("scene-lines");
  gutter.replaceChildren();
  for (let i = 1; i <= count; i++) {
    const n = document.createElement("span");
    n.textContent = `${i}\n`;
    if (i === badLine) n.className = "bad";
    gutter.appendChild(n);
  }
  gutter.scrollTop = $("scene-text").scrollTop;
}
$("scene-text").addEventListener("scroll", () => {
  const area = $("scene-text");
  $("scene-lines").scrollTop = area.scrollTop;
  $("scene-marks").scrollTop = area.scrollTop;
  $("scene-marks").scrollLeft = area.scrollLeft;
});

// Marks `length` characters (at least one) from 1-based `line` and `column` of the scene
// text, behind the textarea (no mark: line 0).
function markSceneText(line = 0, column = 1, length = 1) {
  const marks = $("scene-marks");
  marks.replaceChildren();
  if (!line) return;
  const lines = $("scene-text").value.split("\n");
  const text = lines[line - 1] ?? "";
  const at = Math.min(text.length, Math.max(0, column - 1));
  const mark = document.createElement("mark");
  mark.textContent = text.slice(at, at + Math.max(1, length)) || " ";
  mark.dataset.line = line;
  mark.dataset.column = at + 1;
  // Lines above the mark keep their height; the text itself is transparent.
  marks.append(lines.slice(0, line - 1).map((l) => l + "\n").join("") + text.slice(0, at), mark, "\n");
  marks.scrollTop = $("scene-text").scrollTop;
  marks.scrollLeft = $("scene-text").scrollLeft;
}

$("scene-file").addEventListener("change", () => {
  const entry = hello.scenes.find(([n]) => n === $("scene-file").value);
  if (entry) openScene(entry[0], entry[1]);
  update();
});
$("scene-text").addEventListener("input", () => {
  state.sceneText = $("scene-text").value;
  markSceneText();
  showLineNumbers();
  const c = cameraFromText(state.sceneText);
  if (c) state.camera = c;
  updateSoon(typingPause());
});

function setMode(mode) {
  state.mode = mode;
  $("equation-mode").hidden = mode !== "equation";
  $("scene-mode").hidden = mode !== "scene";
  $("mode-equation").classList.toggle("active", mode === "equation");
  $("mode-scene").classList.toggle("active", mode === "scene");
  $("mode-equation").setAttribute("aria-pressed", String(mode === "equation"));
  $("mode-scene").setAttribute("aria-pressed", String(mode === "scene"));
  if (mode === "equation" && !equationReady) choosePreset(state.presetId || "heart");
  if (mode === "scene") {
    const c = cameraFromText(state.sceneText);
    if (c) state.camera = c;
  }
  clearProblem();
  update();
}
// The Save fields show what will be saved: clamped to the server's limits, with a sentence.
function clampSaveFields() {
  if (!hello) return;
  const l = hello.limits;
  const asked = ["save-width", "save-height", "save-spp"].map((id) => Math.round(Number($(id).value)));
  let [w, h] = saveSize();
  if (w * h > l.max_save_pixels) {
    const k = Math.sqrt(l.max_save_pixels / (w * h));
    [w, h] = [Math.max(1, Math.floor(w * k)), Math.max(1, Math.floor(h * k))];
  }
  const spp = clamp(saveSpp(), 1, Math.max(1, Math.floor(l.max_save_samples / (w * h))));
  if (asked[0] === w && asked[1] === h && asked[2] === spp) return;
  [$("save-width").value, $("save-height").value, $("save-spp").value] = [w, h, spp];
  say(`A saved image is at most ${l.max_save_side} px a side, ${l.max_save_pixels} pixels and ` +
    `${l.max_save_spp} samples a pixel (${l.max_save_samples} samples in all): ${w}×${h} at ${spp} spp is used.`);
}
for (const id of ["save-width", "save-height", "save-spp"]) {
  $(id).addEventListener("change", () => {
    clampSaveFields();
    update();
  });
}
$("study").addEventListener("change", () => {
  state.view = $("study").value;
  showLegend();
  update();
});

// The study view's legend, as the server's library defines it (its colours are the PNG's).
let legends = {};
function showLegend() {
  const box = $("legend");
  const legend = legends[state.view];
  $("probe").hidden = !legend;
  $("probe").textContent = legend ? "hover or tap a pixel: what the root finder did there" : "";
  box.hidden = !legend;
  box.replaceChildren();
  if (!legend) return;
  const title = document.createElement("p");
  title.className = "legend-title";
  title.textContent = legend.title;
  const list = document.createElement("ul");
  for (const [label, colour] of legend.swatches) {
    const item = document.createElement("li");
    const chip = document.createElement("span");
    chip.className = "swatch";
    chip.style.background = colour;
    chip.dataset.colour = colour;
    item.append(chip, label);
    item.dataset.label = label;
    list.appendChild(item);
  }
  box.append(title, list);
  if (legend.note) {
    const note = document.createElement("p");
    note.className = "hint";
    note.textContent = legend.note;
    box.appendChild(note);
  }
}
$("mode-equation").onclick = () => setMode("equation");
$("mode-scene").onclick = () => setMode("scene");

// ---------- errors ----------
function clearProblem() {
  $("problem").classList.remove("shown");
  $("problem").textContent = "";
  $("equation-problem").classList.remove("shown", "notice");
  $("equation-sentence").textContent = "";
  $("equation-marked").replaceChildren();
  $("equation").classList.remove("bad");
  $("equation").removeAttribute("aria-invalid");
  $("scene-text").classList.remove("bad");
  markSceneText();
  canvas.classList.remove("stale");
  showLineNumbers();
  window.kardia.lastProblem = null;
}

// Says why the image is only the background: a surface with no real points inside its clip
// radius (the server's load-time extent is certified, so this is never a guess).
function showNothingToDraw() {
  $("equation-sentence").textContent =
    `Nothing to draw: this surface has no real points inside the clip radius ${fmt(state.bound)}.`;
  $("equation-problem").classList.add("shown", "notice");
}

// The problem in one plain sentence: the parser's message without its place (file:line:
// column), the "invalid equation" heading, or any usage text of the scene language.
function plainSentence(message) {
  let text = message.split("\n")[0].replace(/^.*?:\d+:\d+:\s*/, "");
  text = text.replace(/^invalid equation:\s*/i, "").replace(/\s*usage:.*$/i, "");
  text = text.charAt(0).toUpperCase() + text.slice(1);
  return /[.!?]$/.test(text) ? text : text + ".";
}

function showProblem(problemSeq, problem) {
  if (problemSeq !== seq) return;
  window.kardia.lastProblem = problem;
  window.kardia.problems.push(problem);
  canvas.classList.add("stale");
  if (state.mode === "equation") {
    const info = equationScene();
    $("equation").classList.add("bad");
    $("equation").setAttribute("aria-invalid", "true");
    const onEquation = info.equationColumn && problem.line === info.surfaceLine && info.from;
    const sentence = onEquation ? plainSentence(problem.message)
      : "This surface cannot be drawn: " + plainSentence(problem.message).replace(/^./, (c) => c.toLowerCase());
    $("equation-sentence").textContent = sentence;
    const marked = $("equation-marked");
    marked.replaceChildren();
    if (onEquation) {
      // Map the position in the sent text back to the typed text (letters were replaced).
      const sentAt = Math.max(0, problem.column - info.equationColumn);
      const sentEnd = sentAt + Math.max(1, problem.length);
      const eq = state.equation;
      const at = Math.min(eq.length, info.from[Math.min(sentAt, info.from.length - 1)]);
      const end = Math.max(at + 1, Math.min(eq.length, info.from[Math.min(sentEnd, info.from.length - 1)]));
      const before = eq.slice(Math.max(0, at - 24), at);
      const mark = document.createElement("mark");
      mark.textContent = eq.slice(at, end) || " ";
      marked.append((at > 24 ? "…" : "") + before, mark, eq.slice(end, end + 24) + (end + 24 < eq.length ? "…" : ""));
      marked.dataset.offset = at;
      if (document.activeElement !== $("equation")) $("equation").setSelectionRange(at, end);
    }
    $("equation-problem").classList.add("shown");
    setStatus(`error: ${sentence}`, { error: true, progress: 0 });
  } else {
    $("problem").textContent = problem.report || problem.message;
    $("problem").classList.add("shown");
    setStatus(`error on line ${problem.line}: ${plainSentence(problem.message)}`, { error: true, progress: 0 });
    const area = $("scene-text");
    area.classList.add("bad");
    showLineNumbers(problem.line);
    const lines = area.value.split("\n");
    let start = 0;
    for (let i = 0; i < problem.line - 1 && i < lines.length; i++) start += lines[i].length + 1;
    const column = Math.max(0, problem.column - 1);
    markSceneText(problem.line, problem.column, problem.length);
    if (document.activeElement !== area) {
      area.setSelectionRange(start + column, start + column + Math.max(1, problem.length));
      area.scrollTop = Math.max(0, (problem.line - 4) * 16);
    }
  }
}

// ---------- camera ----------
let drag = null;
const pointers = new Map();

function orbit(dx, dy) {
  const c = state.camera;
  const up = unit(c.up);
  let offset = sub(c.eye, c.look);
  offset = rotate(offset, up, -dx * 0.008);
  const right = unit(cross(sub(c.look, c.eye), up));
  const tilted = rotate(offset, right, -dy * 0.008);
  const angle = Math.acos(Math.max(-1, Math.min(1, dot(unit(tilted), up))));
  if (angle > 0.03 && angle < Math.PI - 0.03) offset = tilted;
  c.eye = add(c.look, offset);
}

function pan(dx, dy) {
  const c = state.camera;
  const forward = sub(c.look, c.eye);
  const right = unit(cross(forward, c.up));
  const trueUp = unit(cross(right, forward));
  // A pinhole camera's field of view is horizontal (degrees) and spans the distance to the
  // look-at point; an orthographic camera's `fov` is its view's height in world units.
  const perPixel = c.orthographic ? c.fov / canvas.clientHeight
    : (2 * len(forward) * Math.tan((c.fov * Math.PI) / 360)) / canvas.clientWidth;
  const move = add(mul(right, -dx * perPixel), mul(trueUp, dy * perPixel));
  c.eye = add(c.eye, move);
  c.look = add(c.look, move);
}

function zoom(factor) {
  const c = state.camera;
  if (c.orthographic) {
    // Moving an orthographic eye changes nothing on screen: the view's height is the zoom.
    c.fov = Math.max(1e-6, Math.min(1e6, c.fov * factor));
    return;
  }
  const offset = sub(c.eye, c.look);
  const d = Math.max(1e-3, Math.min(1e4, len(offset) * factor));
  c.eye = add(c.look, mul(unit(offset), d));
}

function cameraChanged() {
  if (state.mode === "scene") {
    state.sceneText = withCamera(state.sceneText, state.camera);
    const area = $("scene-text");
    const pos = area.selectionStart;
    area.value = state.sceneText;
    area.setSelectionRange(pos, pos);
    showLineNumbers();
  }
  update();
}

canvas.addEventListener("pointerdown", (e) => {
  canvas.setPointerCapture(e.pointerId);
  pointers.set(e.pointerId, [e.clientX, e.clientY]);
  drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey };
  canvas.classList.add("dragging");
});
canvas.addEventListener("pointermove", (e) => {
  if (!pointers.has(e.pointerId)) return;
  if (pointers.size === 2) {
    const [a, b] = [...pointers.values()];
    const before = Math.hypot(a[0] - b[0], a[1] - b[1]);
    pointers.set(e.pointerId, [e.clientX, e.clientY]);
    const [c, d] = [...pointers.values()];
    const after = Math.hypot(c[0] - d[0], c[1] - d[1]);
    if (before > 0 && after > 0) zoom(before / after);
    drag = null; // a pinch is not an orbit; the finger left down orbits again from here
    cameraChanged();
    return;
  }
  pointers.set(e.pointerId, [e.clientX, e.clientY]);
  if (!drag) drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey };
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX;
  drag.y = e.clientY;
  if (dx === 0 && dy === 0) return;
  if (drag.pan || e.shiftKey) pan(dx, dy);
  else orbit(dx, dy);
  cameraChanged();
});
const endDrag = (e) => {
  pointers.delete(e.pointerId);
  drag = null;
  if (pointers.size === 0) canvas.classList.remove("dragging");
};
canvas.addEventListener("pointerup", endDrag);

// ---------- the study views' probe: what the root finder did at a pixel ----------
let probeSeq = 0;
let probeTimer = null;
let probeAt = null;
function probe(e) {
  if (!legends[state.view]) return;
  const r = canvas.getBoundingClientRect();
  const x = Math.floor(((e.clientX - r.left) * canvas.width) / r.width);
  const y = Math.floor(((e.clientY - r.top) * canvas.height) / r.height);
  if (x < 0 || y < 0 || x >= canvas.width || y >= canvas.height) return;
  probeAt = [x, y];
  if (probeTimer) return; // at most one probe every 80 ms, of the newest pixel
  const sendProbe = () => {
    probeTimer = null;
    if (!probeAt) return;
    const [px, py] = probeAt;
    probeAt = null;
    probeSeq += 1;
    send({ type: "probe", seq: probeSeq, scene: currentScene(), width: canvas.width, height: canvas.height, x: px, y: py });
    probeTimer = setTimeout(sendProbe, 80);
  };
  sendProbe();
}
canvas.addEventListener("pointermove", (e) => { if (pointers.size === 0) probe(e); });
canvas.addEventListener("pointerdown", (e) => { if (e.pointerType !== "mouse") probe(e); });

const num = (v) => (v === null || v === undefined ? "–" : Number(v.toPrecision(4)).toString());
function onProbe(m) {
  if (m.seq !== probeSeq) return;
  window.kardia.lastProbe = m;
  for (const li of document.querySelectorAll("#legend li")) {
    li.classList.remove("probed");
    li.removeAttribute("aria-current");
  }
  const r = m.report;
  if (!r) {
    $("probe").textContent = `pixel ${m.x}, ${m.y}: no root finder reached (the ray misses every surface's bounds)`;
    return;
  }
  const what = r.hit ? `${r.settled_by} settled the first root, t = ${num(r.t)}`
    : `${r.settled_by} proved there is no root`;
  $("probe").textContent = `pixel ${m.x}, ${m.y}: ${what}; ${r.roots} distinct root${r.roots === 1 ? "" : "s"} ` +
    `in the interval (degree ${r.degree}); ${r.refine_steps} refinement step${r.refine_steps === 1 ? "" : "s"}, ` +
    `${r.splits} split${r.splits === 1 ? "" : "s"}, ${r.queries} quer${r.queries === 1 ? "y" : "ies"}; ` +
    `|∇f| = ${num(r.gradient_norm)}`;
  if (state.view === "path") {
    const li = [...document.querySelectorAll("#legend li")].find((l) => l.dataset.label === r.settled_by);
    if (li) {
      li.classList.add("probed");
      li.setAttribute("aria-current", "true");
    }
  }
}
canvas.addEventListener("pointercancel", endDrag);
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  zoom(Math.exp(Math.max(-100, Math.min(100, e.deltaY)) * 0.002));
  cameraChanged();
}, { passive: false });
// The keyboard: arrows orbit (shift: pan), + and − zoom.
canvas.addEventListener("keydown", (e) => {
  const step = 12;
  const moves = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step] };
  if (moves[e.key]) {
    const [dx, dy] = moves[e.key];
    if (e.shiftKey) pan(dx, dy);
    else orbit(dx, dy);
  } else if (e.key === "+" || e.key === "=") {
    zoom(1 / 1.15);
  } else if (e.key === "-" || e.key === "_") {
    zoom(1.15);
  } else {
    return;
  }
  e.preventDefault();
  cameraChanged();
});
$("reset").onclick = () => {
  state.camera = structuredClone(state.homeCamera);
  cameraChanged();
};

// ---------- export and share ----------
$("save").onclick = () => {
  if (pendingSave) return say("a save is rendering: wait for it or cancel it");
  clampSaveFields();
  const [width, height] = saveSize();
  const spp = saveSpp();
  pendingSave = { seq: seq + 1000000, width, height, spp };
  say(`rendering ${width}×${height} at ${spp} spp…`);
  const bar = $("save-progress");
  bar.value = 0;
  $("save-cancel").disabled = false;
  const alpha = $("save-alpha").checked;
  send({ type: "save", seq: pendingSave.seq, scene: currentScene(), width, height, spp, view: state.view, alpha });
};
$("save-cancel").onclick = () => {
  if (!pendingSave) return;
  send({ type: "cancel_save" });
  say("cancelling the save…");
};
$("save-alpha").addEventListener("change", () => writeUrl());
function endSave() {
  pendingSave = null;
  $("save-cancel").disabled = true;
}
// The save's progress, from the server about every quarter second.
function onSaveProgress(m) {
  if (!pendingSave || m.seq !== pendingSave.seq) return;
  const fraction = m.total > 0 ? m.done / m.total : 0;
  $("save-progress").value = fraction;
  window.kardia.saveProgress.push(fraction);
  const { width, height, spp } = pendingSave;
  say(`rendering ${width}×${height} at ${spp} spp: ${Math.floor(fraction * 100)} %`);
}
// Download STL / 3MF: the server meshes the scene as `kardia mesh` does.
let pendingMesh = null;
let meshSeq = 2000000;
function requestMesh(format) {
  if (pendingMesh) return say("a mesh is being made: wait for it or cancel it");
  meshSeq += 1;
  pendingMesh = { seq: meshSeq, format };
  $("mesh-progress").value = 0;
  $("mesh-cancel").disabled = false;
  say(`meshing the surface for ${format.toUpperCase()}…`);
  send({ type: "mesh", seq: meshSeq, scene: currentScene(), format });
}
$("mesh-stl").onclick = () => requestMesh("stl");
$("mesh-3mf").onclick = () => requestMesh("3mf");
$("mesh-cancel").onclick = () => {
  if (!pendingMesh) return;
  send({ type: "cancel_mesh" });
  say("cancelling the mesh…");
};
function endMesh() {
  pendingMesh = null;
  $("mesh-cancel").disabled = true;
}
function onMeshProgress(m) {
  if (!pendingMesh || m.seq !== pendingMesh.seq) return;
  $("mesh-progress").value = m.fraction;
  window.kardia.meshProgress.push(m.fraction);
  say(`meshing the surface for ${pendingMesh.format.toUpperCase()}: ${Math.floor(m.fraction * 100)} %`);
}
function onMesh(header, payload) {
  if (!pendingMesh || header.seq !== pendingMesh.seq) return;
  endMesh();
  $("mesh-progress").value = 1;
  const type = header.format === "3mf" ? "model/3mf" : "model/stl";
  const blob = new Blob([payload], { type });
  window.kardia.lastMesh = blob;
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = fileName().replace(/\.png$/, "." + header.format);
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  say(`saved ${a.download}: ${header.triangles} triangles, ${header.ms.toFixed(0)} ms`);
}

// Save scene: the scene text exactly as Copy scene copies it, as a .scene file.
$("save-scene").onclick = () => {
  const text = currentScene();
  const blob = new Blob([text], { type: "text/plain" });
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = fileName().replace(/\.png$/, ".scene");
  window.kardia.lastSceneFile = { name: a.download, text };
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  say(`saved ${a.download}`);
};

// A file name from the surface and its parameters.
function fileName() {
  let name;
  if (state.mode === "scene") name = state.sceneName.replace(/^.*\//, "").replace(/\.scene$/, "") || "scene";
  else if (state.presetId) name = [state.presetId, ...state.params.map(fmt)].join("-");
  else name = "equation-" + Object.entries(state.letters).map(([k, v]) => `${k}${fmt(v.value)}`).join("-");
  name = name.replace(/[^A-Za-z0-9._-]+/g, "_").replace(/-+$/, "").slice(0, 80);
  return `kardia-${name}${state.view === "shaded" ? "" : "-" + state.view}.png`;
}

function onPng(header, payload) {
  endSave();
  $("save-progress").value = 1;
  const blob = new Blob([payload], { type: "image/png" });
  window.kardia.lastPng = blob;
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = fileName();
  window.kardia.lastFileName = a.download;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  say(`saved ${a.download}: ${header.width}×${header.height}, ${header.spp} spp, ${header.ms.toFixed(0)} ms`);
}

async function copy(text, what) {
  window.kardia.clipboard = text;
  try {
    await navigator.clipboard.writeText(text);
    say(`${what} copied`);
  } catch {
    say(`${what}: select and copy from the prompt`);
    window.prompt(what, text);
  }
}
$("copy-scene").onclick = () => copy(currentScene(), "scene");
$("copy-link").onclick = () => copy(location.href, "link");

// ---------- the URL ----------
// The page's whole state in the URL's fragment (see docs/explorer.md). Every change replaces
// the current history entry; a view that stays unchanged for a while becomes an entry of its
// own, so Back and Forward step through the views a person settled on.
let settled = "";
let settleTimer = null;
function writeUrl() {
  const q = new URLSearchParams();
  q.set("mode", state.mode);
  const c = state.camera;
  q.set("camera", [...c.eye, ...c.look, ...c.up, c.fov].map(fmt).join(","));
  if (state.mode === "equation") {
    if (state.presetId) q.set("preset", state.presetId);
    else q.set("equation", state.equation);
    if (state.params.length && state.presetId) q.set("params", state.params.map(fmt).join(","));
    const letters = Object.entries(state.letters).filter(([k]) => freeLetters(state.equation).includes(k));
    if (!state.presetId && letters.length) {
      q.set("letters", letters.map(([k, v]) => [k, v.value, v.min, v.max].map((x) => (typeof x === "number" ? fmt(x) : x)).join(":")).join(","));
    }
    if (!state.boundAuto) q.set("bound", fmt(state.bound));
    q.set("outside", state.outside);
    q.set("inside", state.inside);
  } else {
    const original = hello && hello.scenes.find(([n]) => n === state.sceneName);
    q.set("scene", state.sceneName);
    if (!original || withCamera(original[1], state.camera) !== state.sceneText) q.set("text", state.sceneText);
  }
  if (state.view !== "shaded") q.set("view", state.view);
  q.set("save", [...saveSize(), saveSpp()].join("x"));
  if ($("save-alpha").checked) q.set("alpha", "1");
  if (state.mode === "equation") q.set("scale", fmt(state.scale));
  if (state.fixedSize) q.set("size", state.fixedSize.join("x"));
  const hash = "#" + q.toString();
  history.replaceState(null, "", hash);
  clearTimeout(settleTimer);
  settleTimer = setTimeout(() => {
    if (location.hash !== settled) {
      history.replaceState(null, "", settled || hash);
      history.pushState(null, "", hash);
      settled = hash;
    }
  }, 700);
}

window.addEventListener("popstate", () => {
  clearTimeout(settleTimer);
  settled = location.hash;
  equationReady = false;
  applyUrl(true);
});

// Reads the state from the URL: any subset of its keys (the others keep their defaults).
// Returns the messages for what it could not use (and what it did instead).
function readUrl() {
  const q = new URLSearchParams(location.hash.slice(1));
  const messages = [];
  const number = (key, lo, hi) => {
    if (!q.has(key)) return null;
    const v = Number(q.get(key));
    if (!Number.isFinite(v) || q.get(key).trim() === "") {
      messages.push(`The link's ${key} '${q.get(key).slice(0, 20)}' is not a number: the default is used.`);
      return null;
    }
    if (v < lo || v > hi) messages.push(`The link's ${key} ${v} is outside ${lo} to ${hi}: ${clamp(v, lo, hi)} is used.`);
    return clamp(v, lo, hi);
  };
  state.fixedSize = null;
  if (q.has("size")) {
    const size = q.get("size").match(/^(\d+)x(\d+)$/);
    if (!size) messages.push("The link's size is not WIDTHxHEIGHT: the window's size is used.");
    else {
      const asked = [Number(size[1]), Number(size[2])];
      state.fixedSize = clampViewSize(asked);
      if (state.fixedSize[0] !== asked[0] || state.fixedSize[1] !== asked[1]) {
        messages.push(`The link's size ${asked.join("×")} is over the limits: ${state.fixedSize.join("×")} is used.`);
      }
    }
  }
  if (q.has("view")) {
    if (hello.views.includes(q.get("view"))) state.view = q.get("view");
    else messages.push(`Unknown view '${q.get("view").slice(0, 20)}': the shaded view is shown.`);
  } else {
    state.view = "shaded";
  }
  if (q.has("save")) {
    const save = q.get("save").match(/^(\d+)x(\d+)x(\d+)$/);
    if (save) {
      const l = hello.limits;
      const w = clamp(Number(save[1]), 1, l.max_save_side), h = clamp(Number(save[2]), 1, l.max_save_side);
      const spp = clamp(Number(save[3]), 1, l.max_save_spp);
      if (w !== Number(save[1]) || h !== Number(save[2]) || spp !== Number(save[3])) {
        messages.push(`The link's save size is over the limits: ${w}×${h} at ${spp} spp is used.`);
      }
      [$("save-width").value, $("save-height").value, $("save-spp").value] = [w, h, spp];
    } else messages.push("The link's save is not WIDTHxHEIGHTxSPP: the defaults are used.");
  }
  $("save-alpha").checked = q.get("alpha") === "1";
  const mode = q.get("mode");
  if (mode !== null && mode !== "equation" && mode !== "scene") {
    messages.push(`Unknown mode '${mode.slice(0, 20)}': equation mode is shown.`);
  }
  if (mode === "scene" || (mode === null && (q.has("scene") || q.has("text")))) state.mode = "scene";
  else if (mode !== null || q.has("preset") || q.has("equation")) state.mode = "equation";
  state.scaleFromUrl = false;
  state.boundFromUrl = false;
  if (state.mode === "equation") {
    const scale = number("scale", 1e-3, 1e3);
    if (scale !== null) { state.scale = scale; state.scaleFromUrl = true; }
    state.presetId = null;
    if (q.has("preset")) {
      if (presetById(q.get("preset"))) state.presetId = q.get("preset");
      else messages.push(`Unknown surface '${q.get("preset").slice(0, 30)}': the heart is shown instead.`);
    }
    if (!state.presetId && q.has("equation")) {
      state.equation = q.get("equation");
    } else if (!state.presetId) {
      state.presetId = "heart";
    }
    state.params = (q.get("params") || "").split(",").filter((v) => v.trim() !== "").map(Number);
    if (state.params.some((v) => !Number.isFinite(v))) {
      messages.push("The link's params are not numbers: the defaults are used.");
      state.params = [];
    }
    const p = state.presetId && presetById(state.presetId);
    if (p && q.has("params") && state.params.length !== p.sliders.length) {
      messages.push(`${p.title} takes ${p.sliders.length} parameters: the defaults are used.`);
    }
    if (p && state.params.length === p.sliders.length) {
      p.sliders.forEach((s, i) => {
        if (state.params[i] < s.min || state.params[i] > s.max) {
          messages.push(`${s.label} ${state.params[i]} is outside ${s.min} to ${s.max}.`);
        }
      });
    }
    const bound = number("bound", 1e-3, 1e6);
    if (bound !== null) { state.bound = bound; state.boundAuto = false; state.boundFromUrl = true; }
    state.letters = {};
    for (const item of (q.get("letters") || "").split(",").filter(Boolean)) {
      const [k, ...nums] = item.split(":");
      const [value, min, max] = nums.map(Number);
      if (k && k.length === 1 && [value, min, max].every(Number.isFinite) && min <= max) {
        state.letters[k] = { value: clamp(value, min, max), min, max };
      } else messages.push(`The link's letter '${item.slice(0, 20)}' is not NAME:VALUE:MIN:MAX.`);
    }
    const colour = (key) => {
      if (!q.has(key)) return;
      if (/^#[0-9a-fA-F]{6}$/.test(q.get(key))) state[key] = q.get(key).toLowerCase();
      else messages.push(`The link's ${key} colour is not #rrggbb: the default is used.`);
    };
    colour("outside");
    colour("inside");
    $("outside").value = state.outside;
    $("inside").value = state.inside;
    $("equation").value = state.equation;
  } else {
    const name = q.get("scene") || hello.initial[0];
    const entry = hello.scenes.find(([n]) => n === name) || (name === hello.initial[0] ? hello.initial : null);
    if (!entry && !q.has("text")) messages.push(`Unknown scene '${name.slice(0, 40)}': the first scene is shown.`);
    openScene(entry ? name : hello.initial[0], q.get("text") || (entry ? entry[1] : hello.initial[1]));
  }
  if (q.has("camera")) {
    const nums = q.get("camera").split(",").map(Number);
    // The projection is the scene text's (its CAMERA line); the link holds the view. An
    // orthographic camera's last number is its view's height, not an angle.
    const orthographic = state.mode === "scene" && Boolean(cameraFromText(state.sceneText)?.orthographic);
    const camera = { eye: nums.slice(0, 3), look: nums.slice(3, 6), up: nums.slice(6, 9), fov: nums[9], orthographic };
    const ok = nums.length === 10 && nums.every(Number.isFinite) && camera.fov > 0 && (orthographic || camera.fov < 180) &&
      len(sub(camera.eye, camera.look)) > 0 && len(cross(sub(camera.look, camera.eye), camera.up)) > 0;
    if (ok) {
      state.camera = camera;
      if (state.mode === "scene") state.sceneText = withCamera(state.sceneText, state.camera);
      $("scene-text").value = state.sceneText;
    } else {
      messages.push("The link's camera is not 10 numbers of a valid view: the default view is used.");
      if (state.mode === "equation") state.camera = structuredClone(DEFAULT_CAMERA);
    }
  } else if (state.mode === "equation") {
    state.camera = structuredClone(DEFAULT_CAMERA);
  }
  if (state.mode === "equation") state.homeCamera = structuredClone(DEFAULT_CAMERA);
  return messages;
}

// A hidden page stops its refinement (the server renders nothing for it) and asks for its
// view again when shown.
document.addEventListener("visibilitychange", () => {
  if (document.visibilityState === "hidden") {
    clearTimeout(pendingTimer);
    send({ type: "pause" });
    window.kardia.paused = true;
  } else {
    window.kardia.paused = false;
    lastText = "";
    update();
  }
});

new ResizeObserver(() => update()).observe(canvas);
connect();
