// The JS API the page is built on (docs/web.md): `window.lambert`, for
// tests and for embedding lambert in another page. It wraps the wasm
// crate (pkg/lambert_web.js, written by scripts/build-web) and opens one
// WebGPU session, which every render shares.
import init, { Session } from "./pkg/lambert_web.js";

/** Why lambert cannot run here, in words a visitor can act on. */
function noWebGpu(detail) {
  return new Error(
    `lambert needs WebGPU, and ${detail}. Use a browser with WebGPU ` +
      "(Chrome or Edge 113 or later, Safari 26, Firefox 141 on Windows), over " +
      "https or localhost; on Linux, Chromium may need --enable-unsafe-webgpu.",
  );
}

async function open() {
  if (!("gpu" in navigator) || !navigator.gpu) {
    throw noWebGpu("this browser has none (navigator.gpu is missing)");
  }
  await init();
  try {
    return await Session.open();
  } catch (e) {
    throw noWebGpu(`no WebGPU adapter opened (${e && e.message ? e.message : e})`);
  }
}

const session = open();

/** Resolves once wasm is initialised and a WebGPU session is open; rejects
 * with the no-WebGPU message otherwise. */
export const ready = session.then(() => undefined);
// The page reports a rejection itself; an embedder awaits `ready`.
ready.catch(() => {});

/** The name of the WebGPU adapter lambert renders on (after `ready`). */
export let adapter = null;
session.then((s) => {
  adapter = s.adapter();
}, () => {});

/**
 * Ray traces a model file's bytes (`name` gives its format by extension:
 * .glb, .gltf with embedded buffers, .obj, .ply, .stl) as
 * `lambert render NAME --width W --height H --spp N` does: the file's camera
 * or the framed one, its lights or the default light. Options left out take
 * the CLI's defaults (a model's 1024 × 768, or its glTF camera's aspect;
 * 1 spp; with only one of width and height, the other keeps the aspect).
 * Returns {width, height, pixels}: linear RGB floats, rows top to bottom.
 */
export async function renderModel(bytes, name, { width, height, spp } = {}) {
  const s = await session;
  return s.renderModel(bytes, name, width, height, spp);
}

/** A progressive view of a model file (the page's): see Viewer in docs/web.md. */
export async function openModel(bytes, name) {
  const s = await session;
  return s.openModel(bytes, name);
}

window.lambert = {
  ready,
  renderModel,
  openModel,
  get adapter() {
    return adapter;
  },
};
