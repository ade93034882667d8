// The page (docs/web.md): a model dropped or picked is ray traced
// progressively on the visitor's GPU, as `lambert view` does, through the
// same API an embedder uses (lambert.js).
import * as lambert from "./lambert.js";

// `lambert view`'s default: refine up to 1024 spp, then rest.
const MAX_SPP = 1024;
// A batch of samples is sized to take about this long, so that input is
// answered promptly on a slow adapter and a fast one is not held back by
// one readback per sample.
const BATCH_SECONDS = 0.05;

const $ = (id) => document.getElementById(id);
const canvas = $("view");
const context = canvas.getContext("2d");

let viewer = null;
let modelName = null;
// Input is gathered here and handed to the viewer between batches: the
// viewer is busy (borrowed by wasm) while a batch is in flight.
let pending = freshInput();
let wake = null;

function freshInput() {
  return { orbit: [0, 0], pan: [0, 0], dolly: 0, reset: false, size: null };
}

function showMessage(text) {
  $("message").textContent = text;
  $("message").hidden = !text;
}

function kick() {
  if (wake) {
    const w = wake;
    wake = null;
    w();
  }
}

/** The render size: the canvas's size on the page, in CSS pixels. */
function canvasSize() {
  const r = canvas.getBoundingClientRect();
  return [Math.max(1, Math.round(r.width)), Math.max(1, Math.round(r.height))];
}

/** Hands the input gathered since the last batch to `v`; true when the
 * view changed (and so its samples started again). */
function applyInput(v) {
  const p = pending;
  pending = freshInput();
  let changed = false;
  if (p.size && (p.size[0] !== v.width() || p.size[1] !== v.height())) {
    v.resize(p.size[0], p.size[1]);
    changed = true;
  }
  if (p.reset) {
    v.resetCamera();
    changed = true;
  }
  if (p.orbit[0] || p.orbit[1]) {
    v.orbit(p.orbit[0], p.orbit[1]);
    changed = true;
  }
  if (p.pan[0] || p.pan[1]) {
    v.pan(p.pan[0], p.pan[1]);
    changed = true;
  }
  if (p.dolly) {
    v.dolly(p.dolly);
    changed = true;
  }
  return changed;
}

function draw(v) {
  const w = v.width();
  const h = v.height();
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  const rgba = v.rgba();
  context.putImageData(new ImageData(new Uint8ClampedArray(rgba.buffer, rgba.byteOffset, rgba.length), w, h), 0, 0);
}

/** The progressive loop: batches of samples until MAX_SPP, each drawn;
 * Mrays/s is rays traced (width·height·rays per sample·samples) over the
 * wall time of the batches since the view last changed. */
async function refine(v) {
  try {
    await refineWhileShown(v);
  } finally {
    // Freed here, not by the load that replaced it: a batch in flight
    // holds it until it ends.
    v.free();
  }
}

async function refineWhileShown(v) {
  let rays = 0;
  let seconds = 0;
  let batch = 1;
  while (v === viewer) {
    if (applyInput(v)) {
      rays = 0;
      seconds = 0;
    }
    if (v.spp() >= MAX_SPP) {
      await new Promise((resolve) => (wake = resolve));
      continue;
    }
    const before = v.spp();
    const n = Math.min(batch, MAX_SPP - before);
    const start = performance.now();
    const total = await v.addSamples(n);
    const elapsed = (performance.now() - start) / 1000;
    if (v !== viewer) return;
    rays += v.width() * v.height() * v.raysPerSample() * (total - before);
    seconds += elapsed;
    draw(v);
    $("spp").textContent = String(total);
    $("mrays").textContent = seconds > 0 ? (rays / seconds / 1e6).toFixed(2) : "–";
    batch = Math.max(1, Math.min(64, Math.round((n * BATCH_SECONDS) / Math.max(elapsed, 1e-3))));
    // Let input and painting in before the next batch.
    await new Promise((resolve) => setTimeout(resolve, 0));
  }
}

async function load(bytes, name) {
  showMessage("");
  $("model").textContent = `${name} (loading…)`;
  let v;
  try {
    await lambert.ready;
    v = await lambert.openModel(bytes, name);
  } catch (e) {
    $("model").textContent = "none";
    showMessage(e && e.message ? e.message : String(e));
    return;
  }
  viewer = v;
  modelName = name;
  pending = freshInput();
  pending.size = canvasSize();
  $("model").textContent = name;
  $("hint").hidden = true;
  $("spp").textContent = "0";
  $("mrays").textContent = "–";
  $("reset").disabled = false;
  $("save").disabled = false;
  const list = $("warnings");
  list.replaceChildren(
    ...v.warnings().map((w) => {
      const li = document.createElement("li");
      li.textContent = `warning: ${w}`;
      return li;
    }),
  );
  kick();
  refine(v).catch((e) => showMessage(`rendering ${name} failed: ${e && e.message ? e.message : e}`));
}

async function loadFile(file) {
  if (file) load(new Uint8Array(await file.arrayBuffer()), file.name);
}

$("file").addEventListener("change", (e) => loadFile(e.target.files[0]));

for (const button of document.querySelectorAll("button.demo")) {
  button.addEventListener("click", async () => {
    const url = button.dataset.model;
    const response = await fetch(url);
    if (!response.ok) {
      showMessage(`${url}: ${response.status} ${response.statusText}`);
      return;
    }
    load(new Uint8Array(await response.arrayBuffer()), url.split("/").pop());
  });
}

const drop = $("drop");
drop.addEventListener("dragover", (e) => {
  e.preventDefault();
  drop.classList.add("over");
});
drop.addEventListener("dragleave", () => drop.classList.remove("over"));
drop.addEventListener("drop", (e) => {
  e.preventDefault();
  drop.classList.remove("over");
  loadFile(e.dataTransfer.files[0]);
});

$("reset").addEventListener("click", () => {
  pending.reset = true;
  kick();
});

$("save").addEventListener("click", () => {
  if (!viewer) return;
  const blob = new Blob([viewer.png()], { type: "image/png" });
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = `${modelName.replace(/\.[^.]*$/, "")}.png`;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 0);
});

// Left drag orbits; right, middle or shift drag pans; the wheel dollies.
let drag = null;
canvas.addEventListener("contextmenu", (e) => e.preventDefault());
canvas.addEventListener("pointerdown", (e) => {
  drag = { x: e.clientX, y: e.clientY, pan: e.button !== 0 || e.shiftKey };
  canvas.setPointerCapture(e.pointerId);
});
canvas.addEventListener("pointermove", (e) => {
  if (!drag || !viewer) return;
  const d = drag.pan ? pending.pan : pending.orbit;
  d[0] += e.clientX - drag.x;
  d[1] += e.clientY - drag.y;
  drag.x = e.clientX;
  drag.y = e.clientY;
  kick();
});
canvas.addEventListener("pointerup", () => (drag = null));
canvas.addEventListener("pointercancel", () => (drag = null));
canvas.addEventListener(
  "wheel",
  (e) => {
    e.preventDefault();
    // A wheel notch: 100 pixels in Chromium, 3 lines in Firefox; up (a
    // negative deltaY) dollies in, as lambert view's wheel does.
    const perStep = e.deltaMode === 0 ? 100 : e.deltaMode === 1 ? 3 : 1;
    pending.dolly -= e.deltaY / perStep;
    kick();
  },
  { passive: false },
);
new ResizeObserver(() => {
  pending.size = canvasSize();
  kick();
}).observe(canvas);

lambert.ready.then(
  () => ($("adapter").textContent = lambert.adapter),
  (e) => {
    $("adapter").textContent = "none";
    showMessage(e.message);
    for (const b of document.querySelectorAll("button, input")) b.disabled = true;
  },
);

// Offline once loaded: the service worker caches the page, its scripts
// and the wasm. Registered only where the page is served over http(s).
if ("serviceWorker" in navigator && location.protocol.startsWith("http")) {
  navigator.serviceWorker.register("sw.js").catch((e) => console.warn(`no offline copy: ${e}`));
}
