// kardia explore: the page. Plain JavaScript, no dependencies. Every view is sent to the
// server as a whole scene text (the text is the one truth: "Copy scene" is exactly what was
// rendered); frames come back as raw RGBA and are drawn on the canvas.
"use strict";

const $ = (id) => document.getElementById(id);
const canvas = $("view");
const ctx = canvas.getContext("2d");

const DEFAULT_CAMERA = { eye: [6, 1.2, 0.9], look: [0, 0, 0.05], up: [0, 0, 1], fov: 32 };

const state = {
  mode: "scene",          // "equation" | "scene"
  presetId: "heart",      // gallery entry, or null for a typed equation
  params: [],             // the preset's parameters
  scale: 1,               // object-space scale of the placed surface
  equation: "",           // typed (or expanded) equation text
  bound: 2,
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
window.kardia = { state, frames: [], errors: [], lastProblem: null, sent: () => seq, currentScene: () => currentScene() };

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
  if (i < 0) return line + "\n" + text;
  lines[i] = line + (lines[i].endsWith("\r") ? "\r" : "");
  return lines.join("\n");
}

// Equation mode's scene; also records where the surface is written, to map errors back.
function equationScene() {
  const s = fmt(state.scale);
  const preset = state.presetId && presetById(state.presetId);
  let surface;
  if (preset && preset.preset) {
    surface = [preset.preset, ...state.params.map(fmt)].join(" ");
  } else {
    surface = `"${state.equation.replace(/[\r\n"]+/g, " ")}"`;
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
  const line = `${prefix}${surface} (0, 0, 0) (${s}, 0, 0) (0, ${s}, 0) (0, 0, ${s}) ` +
    `${vec(srgbToLinear(state.outside))} SPECULAR 0.4 60 INSIDE ${vec(srgbToLinear(state.inside))} ` +
    `BOUND ${fmt(state.bound)}`;
  return {
    text: [...head, line, ""].join("\n"),
    surfaceLine: head.length + 1,
    // 1-based column of the equation's first character (after the quote).
    equationColumn: surface.startsWith('"') ? prefix.length + 2 : null,
  };
}

function currentScene() {
  if (state.mode === "equation") return equationScene().text;
  return withCamera(state.sceneText, state.camera);
}

function saveSize() {
  return [Number($("save-width").value) || 800, Number($("save-height").value) || 600];
}

function viewSize() {
  if (state.fixedSize) return state.fixedSize;
  const r = canvas.getBoundingClientRect();
  return [Math.max(16, Math.round(r.width)), Math.max(16, Math.round(r.height))];
}

// ---------- talking to the server ----------
function connect() {
  socket = new WebSocket(`ws://${location.host}/ws`);
  socket.binaryType = "arraybuffer";
  socket.onmessage = (e) => (typeof e.data === "string" ? onText(JSON.parse(e.data)) : onBinary(e.data));
  socket.onclose = (e) => {
    $("status").textContent = `disconnected (${e.code}${e.reason ? ": " + e.reason : ""}); reload the page`;
  };
}

function send(message) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}

// Sends the current view (only when something changed).
function update() {
  if (!hello) return; // the URL's state is read once the server has said hello
  const text = currentScene();
  const [width, height] = viewSize();
  const key = `${width}x${height} ${state.view}\n${text}`;
  if (key === lastText) return;
  lastText = key;
  if (canvas.width !== width || canvas.height !== height) {
    canvas.width = width;
    canvas.height = height;
  }
  seq += 1;
  stats.firstInput = performance.now();
  send({ type: "view", seq, scene: text, width, height, view: state.view });
  writeUrl();
}

function onText(m) {
  if (m.type === "hello") return onHello(m);
  if (m.type === "scene_error") return showProblem(m.seq, m.problem);
  if (m.type === "preset") return onPreset(m);
  if (m.type === "error") {
    window.kardia.errors.push(m.message);
    $("message").textContent = m.message;
  }
}

function onBinary(buffer) {
  const view = new DataView(buffer);
  const n = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, n)));
  const payload = new Uint8Array(buffer, 4 + n);
  if (header.type === "png") return onPng(header, payload);
  if (header.seq < drawnSeq) return;
  if (header.seq > drawnSeq) clearProblem();
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
  const ms = performance.now() - stats.firstInput;
  window.kardia.frames.push({ ...header, sinceInput: ms });
  if (window.kardia.frames.length > 1000) window.kardia.frames.shift();
  const rate = header.ms > 0 ? header.rays / (header.ms / 1000) : 0;
  $("status").textContent =
    `${header.width}×${header.height}` +
    (header.width !== header.view_width ? ` (of ${header.view_width}×${header.view_height})` : "") +
    ` · ${header.spp} spp · ${header.ms.toFixed(0)} ms/pass · ${(rate / 1e6).toFixed(2)} M rays/s` +
    (header.done ? " · done" : "");
}

function onHello(m) {
  hello = m;
  const gallery = $("gallery");
  gallery.innerHTML = "";
  for (const p of m.presets) {
    const b = document.createElement("button");
    b.textContent = p.title;
    b.title = p.about;
    b.dataset.preset = p.id;
    b.onclick = () => choosePreset(p.id);
    gallery.appendChild(b);
  }
  const about = document.createElement("p");
  about.id = "about";
  gallery.after(about);
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
  const fromUrl = readUrl();
  study.value = state.view;
  showLegend();
  if (!fromUrl) {
    openScene(m.initial[0], m.initial[1]);
  }
  if (state.mode === "equation") choosePreset(state.presetId, { keepParams: fromUrl, keepView: fromUrl });
  setMode(state.mode);
}

function presetById(id) {
  return hello && hello.presets.find((p) => p.id === id);
}

// ---------- equation mode ----------
let equationReady = false; // equation mode has a surface
function choosePreset(id, { keepParams = false, keepView = false } = {}) {
  equationReady = true;
  const p = presetById(id);
  if (!p) {
    state.presetId = null;
    renderSliders();
    update();
    return;
  }
  state.presetId = id;
  state.scale = p.scale;
  if (!keepParams) {
    state.params = p.sliders.map((s) => s.value);
    state.bound = p.bound;
  }
  if (!keepView) {
    state.camera = structuredClone(DEFAULT_CAMERA);
    state.homeCamera = structuredClone(DEFAULT_CAMERA);
  }
  for (const b of document.querySelectorAll("#gallery button")) b.classList.toggle("active", b.dataset.preset === id);
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

function onPreset(m) {
  const p = state.presetId && presetById(state.presetId);
  if (!p || p.preset !== m.name || m.params.some((v, i) => v !== state.params[i])) return;
  state.equation = m.equation;
  $("equation").value = m.equation;
  if (!m.params.length) return;
}

function renderSliders() {
  const box = $("sliders");
  box.innerHTML = "";
  const p = state.presetId && presetById(state.presetId);
  if (p) {
    p.sliders.forEach((s, i) => {
      const div = document.createElement("div");
      div.className = "slider";
      const label = document.createElement("label");
      const out = document.createElement("output");
      out.textContent = fmt(state.params[i]);
      label.append(`${s.label} `, out);
      const input = document.createElement("input");
      Object.assign(input, { type: "range", min: s.min, max: s.max, step: s.step, value: state.params[i] });
      input.id = `param-${i}`;
      input.oninput = () => {
        state.params[i] = Number(input.value);
        out.textContent = fmt(state.params[i]);
        send({ type: "preset", name: p.preset, params: state.params });
        update();
      };
      div.append(label, input);
      box.appendChild(div);
    });
  }
  $("bound").value = state.bound;
  $("bound-value").textContent = fmt(state.bound);
}

$("equation").addEventListener("input", () => {
  state.presetId = null;
  state.equation = $("equation").value;
  for (const b of document.querySelectorAll("#gallery button")) b.classList.remove("active");
  renderSliders();
  update();
});
$("bound").addEventListener("input", () => {
  state.bound = Number($("bound").value);
  $("bound-value").textContent = fmt(state.bound);
  update();
});
for (const id of ["outside", "inside"]) {
  $(id).addEventListener("input", () => {
    state[id] = $(id).value;
    update();
  });
}

// ---------- scene mode ----------
function openScene(name, text) {
  state.sceneName = name;
  state.sceneText = text;
  $("scene-text").value = text;
  const select = $("scene-file");
  if ([...select.options].some((o) => o.value === name)) select.value = name;
  const c = cameraFromText(text);
  if (c) {
    state.camera = c;
    state.homeCamera = structuredClone(c);
  }
}

$("scene-file").addEventListener("change", () => {
  const entry = hello.scenes.find(([n]) => n === $("scene-file").value);
  if (entry) openScene(entry[0], entry[1]);
  update();
});
$("scene-text").addEventListener("input", () => {
  state.sceneText = $("scene-text").value;
  const c = cameraFromText(state.sceneText);
  if (c) state.camera = c;
  update();
});

function setMode(mode) {
  state.mode = mode;
  $("equation-mode").hidden = mode !== "equation";
  $("scene-mode").hidden = mode !== "scene";
  $("mode-equation").classList.toggle("active", mode === "equation");
  $("mode-scene").classList.toggle("active", mode === "scene");
  if (mode === "equation" && !equationReady) choosePreset(state.presetId || "heart");
  if (mode === "scene") {
    const c = cameraFromText(state.sceneText);
    if (c) state.camera = c;
  }
  clearProblem();
  update();
}
for (const id of ["save-width", "save-height", "save-spp"]) $(id).addEventListener("change", () => update());
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
  $("problem").hidden = true;
  $("equation-marked").hidden = true;
  $("equation").classList.remove("bad");
  $("scene-text").classList.remove("bad");
  window.kardia.lastProblem = null;
}

function showProblem(problemSeq, problem) {
  if (problemSeq !== seq) return;
  window.kardia.lastProblem = problem;
  $("problem").textContent = problem.report || problem.message;
  $("problem").hidden = false;
  $("status").textContent = problem.message;
  if (state.mode === "equation") {
    const info = equationScene();
    $("equation").classList.add("bad");
    if (info.equationColumn && problem.line === info.surfaceLine) {
      const chars = [...state.equation];
      const at = Math.max(0, Math.min(chars.length, problem.column - info.equationColumn));
      const end = Math.min(chars.length, at + Math.max(1, problem.length));
      const marked = $("equation-marked");
      marked.innerHTML = "";
      const mark = document.createElement("mark");
      mark.textContent = chars.slice(at, end).join("") || " ";
      marked.append(chars.slice(0, at).join(""), mark, chars.slice(end).join(""));
      marked.hidden = false;
      marked.dataset.offset = at;
      const utf16 = (k) => chars.slice(0, k).join("").length;
      if (document.activeElement !== $("equation")) $("equation").setSelectionRange(utf16(at), utf16(end));
    }
  } else {
    const area = $("scene-text");
    area.classList.add("bad");
    const lines = area.value.split("\n");
    let start = 0;
    for (let i = 0; i < problem.line - 1 && i < lines.length; i++) start += lines[i].length + 1;
    const lineText = lines[problem.line - 1] || "";
    if (document.activeElement !== area) {
      area.setSelectionRange(start, start + lineText.length);
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
  const perPixel = (2 * len(forward) * Math.tan((c.fov * Math.PI) / 360)) / canvas.clientWidth;
  const move = add(mul(right, -dx * perPixel), mul(trueUp, dy * perPixel));
  c.eye = add(c.eye, move);
  c.look = add(c.look, move);
}

function zoom(factor) {
  const c = state.camera;
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
    cameraChanged();
    return;
  }
  pointers.set(e.pointerId, [e.clientX, e.clientY]);
  if (!drag) return;
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX;
  drag.y = e.clientY;
  if (drag.pan || e.shiftKey) pan(dx, dy);
  else orbit(dx, dy);
  cameraChanged();
});
const endDrag = (e) => {
  pointers.delete(e.pointerId);
  if (pointers.size === 0) {
    drag = null;
    canvas.classList.remove("dragging");
  }
};
canvas.addEventListener("pointerup", endDrag);
canvas.addEventListener("pointercancel", endDrag);
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  zoom(Math.exp(Math.max(-100, Math.min(100, e.deltaY)) * 0.002));
  cameraChanged();
}, { passive: false });
$("reset").onclick = () => {
  state.camera = structuredClone(state.homeCamera);
  cameraChanged();
};

// ---------- export and share ----------
$("save").onclick = () => {
  const [width, height] = saveSize();
  const spp = Number($("save-spp").value) || 1;
  pendingSave = { seq: seq + 1000000 };
  $("message").textContent = `rendering ${width}×${height} at ${spp} spp…`;
  const alpha = $("save-alpha").checked;
  send({ type: "save", seq: pendingSave.seq, scene: currentScene(), width, height, spp, view: state.view, alpha });
};
$("save-alpha").addEventListener("change", () => writeUrl());

function onPng(header, payload) {
  const blob = new Blob([payload], { type: "image/png" });
  window.kardia.lastPng = blob;
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = "kardia.png";
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  $("message").textContent = `saved ${header.width}×${header.height}, ${header.spp} spp, ${header.ms.toFixed(0)} ms`;
}

async function copy(text, what) {
  window.kardia.clipboard = text;
  try {
    await navigator.clipboard.writeText(text);
    $("message").textContent = `${what} copied`;
  } catch {
    $("message").textContent = `${what}: select and copy from the prompt`;
    window.prompt(what, text);
  }
}
$("copy-scene").onclick = () => copy(currentScene(), "scene");
$("copy-link").onclick = () => copy(location.href, "link");

// The page's whole state in the URL's fragment (see docs/explorer.md).
function writeUrl() {
  const q = new URLSearchParams();
  q.set("mode", state.mode);
  const c = state.camera;
  q.set("camera", [...c.eye, ...c.look, ...c.up, c.fov].map(fmt).join(","));
  if (state.mode === "equation") {
    if (state.presetId) q.set("preset", state.presetId);
    else q.set("equation", state.equation);
    if (state.params.length && state.presetId) q.set("params", state.params.map(fmt).join(","));
    q.set("bound", fmt(state.bound));
    q.set("outside", state.outside);
    q.set("inside", state.inside);
  } else {
    const original = hello && hello.scenes.find(([n]) => n === state.sceneName);
    q.set("scene", state.sceneName);
    if (!original || withCamera(original[1], state.camera) !== state.sceneText) q.set("text", state.sceneText);
  }
  if (state.view !== "shaded") q.set("view", state.view);
  q.set("save", [...saveSize(), Number($("save-spp").value) || 1].join("x"));
  if ($("save-alpha").checked) q.set("alpha", "1");
  if (state.mode === "equation") q.set("scale", fmt(state.scale));
  if (state.fixedSize) q.set("size", state.fixedSize.join("x"));
  history.replaceState(null, "", "#" + q.toString());
}

// Reads the state from the URL; true when it named one.
function readUrl() {
  const q = new URLSearchParams(location.hash.slice(1));
  const size = (q.get("size") || "").match(/^(\d+)x(\d+)$/);
  if (size) state.fixedSize = [Number(size[1]), Number(size[2])];
  if (hello.views.includes(q.get("view"))) state.view = q.get("view");
  const save = (q.get("save") || "").match(/^(\d+)x(\d+)x(\d+)$/);
  if (save) [$("save-width").value, $("save-height").value, $("save-spp").value] = save.slice(1);
  $("save-alpha").checked = q.get("alpha") === "1";
  if (!q.has("mode")) return false;
  if (q.has("scale")) state.scale = Number(q.get("scale")) || 1;
  state.mode = q.get("mode") === "equation" ? "equation" : "scene";
  if (state.mode === "equation") {
    state.presetId = q.get("preset");
    state.equation = q.get("equation") || "";
    state.params = (q.get("params") || "").split(",").filter(Boolean).map(Number);
    if (q.has("bound")) state.bound = Number(q.get("bound"));
    state.outside = q.get("outside") || state.outside;
    state.inside = q.get("inside") || state.inside;
    $("outside").value = state.outside;
    $("inside").value = state.inside;
    $("equation").value = state.equation;
    if (!state.presetId) renderSliders();
  } else {
    const name = q.get("scene") || "";
    const entry = hello.scenes.find(([n]) => n === name) || (name === hello.initial[0] ? hello.initial : null);
    openScene(name, q.get("text") || (entry ? entry[1] : hello.initial[1]));
  }
  const nums = (q.get("camera") || "").split(",").map(Number);
  if (nums.length === 10 && nums.every(Number.isFinite)) {
    state.camera = { eye: nums.slice(0, 3), look: nums.slice(3, 6), up: nums.slice(6, 9), fov: nums[9] };
    if (state.mode === "scene") state.sceneText = withCamera(state.sceneText, state.camera);
    $("scene-text").value = state.sceneText;
  }
  return true;
}

new ResizeObserver(() => update()).observe(canvas);
connect();
