// The page offline once loaded (docs/web.md): everything it needs is
// cached on install and answered from the cache first. scripts/build-web
// writes the build's hash into VERSION, so that a new build's worker
// replaces the old one's cache rather than serving it stale.
const VERSION = "@BUILD@";
const CACHE = `lambert-${VERSION}`;
const FILES = [
  "./",
  "index.html",
  "style.css",
  "app.js",
  "lambert.js",
  "pkg/lambert_web.js",
  "pkg/lambert_web_bg.wasm",
  "models/bunny_lowres.ply",
  "models/boxes.glb",
];

self.addEventListener("install", (event) => {
  event.waitUntil(caches.open(CACHE).then((cache) => cache.addAll(FILES)).then(() => self.skipWaiting()));
});

self.addEventListener("activate", (event) => {
  event.waitUntil(
    caches
      .keys()
      .then((keys) => Promise.all(keys.filter((k) => k.startsWith("lambert-") && k !== CACHE).map((k) => caches.delete(k))))
      .then(() => self.clients.claim()),
  );
});

self.addEventListener("fetch", (event) => {
  if (event.request.method !== "GET") return;
  event.respondWith(caches.match(event.request, { ignoreSearch: true }).then((hit) => hit || fetch(event.request)));
});
