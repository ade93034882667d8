"""Headless Chromium for the web page's tests (test_web.py, docs/web.md):
the page built by scripts/build-web and served on localhost, and Debian's
chromium driven through chromedriver's W3C WebDriver HTTP API with the
standard library alone."""

import base64
import functools
import http.server
import json
import os
import shutil
import socket
import subprocess
import tempfile
import threading
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

from conftest import ROOT, TARGET

CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
CHROMEDRIVER = os.environ.get("CHROMEDRIVER", "/usr/bin/chromedriver")
# This machine's network is closed, and a test's browser starts clean:
# nothing fetched in the background, no first-run pages, no profile kept.
QUIET = ["--headless=new", "--no-sandbox", "--disable-background-networking", "--disable-component-update",
         "--no-first-run", "--disable-sync", "--disable-dev-shm-usage"]
WEBGPU = "--enable-unsafe-webgpu"
# SwiftShader on two shared cores compiles the kernels and traces slowly.
SCRIPT_TIMEOUT_S = 600


def under_ci():
    return os.environ.get("CI", "").lower() in ("true", "1")


def need_chromium():
    """Skips without Chromium and its driver, except under CI (CI=true),
    where scripts/test installs them and their absence fails."""
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not shutil.which(p)]
    if missing:
        why = f"{' and '.join(missing)} missing (Debian's chromium and chromium-driver; scripts/test installs them)"
        if under_ci():
            pytest.fail(f"under CI: {why}")
        pytest.skip(why)


@functools.cache
def built_page():
    """The folder scripts/build-web wrote: LAMBERT_WEB's (scripts/test builds
    it once), else built here into the target directory."""
    out = os.environ.get("LAMBERT_WEB")
    if out:
        if not os.path.exists(os.path.join(out, "pkg", "lambert_web_bg.wasm")):
            pytest.fail(f"LAMBERT_WEB={out} holds no built page (scripts/build-web {out})")
        return out
    out = os.path.join(TARGET, "web")
    done = subprocess.run([os.path.join(ROOT, "scripts", "build-web"), out], capture_output=True, text=True)
    if done.returncode != 0:
        pytest.fail(f"scripts/build-web {out} failed:\n{done.stderr[-4000:]}")
    return out


class Server:
    """A static server of `folder` on localhost, in a thread, until stopped."""

    def __init__(self, folder):
        handler = functools.partial(QuietHandler, directory=folder)
        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    def stop(self):
        self.httpd.shutdown()
        self.httpd.server_close()
        self.thread.join()


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Browser:
    """chromedriver and one headless Chromium session over WebDriver."""

    def __init__(self, webgpu=True):
        self.profile = tempfile.mkdtemp(prefix="lambert-chromium-")
        port = free_port()
        self.log = open(os.path.join(self.profile, "chromedriver.log"), "w")
        self.driver = subprocess.Popen([CHROMEDRIVER, f"--port={port}"], stdout=self.log, stderr=subprocess.STDOUT)
        self.base = f"http://127.0.0.1:{port}"
        self.session = None
        deadline = time.monotonic() + 30
        while True:
            try:
                self.call("GET", "/status")
                break
            except (urllib.error.URLError, ConnectionError):
                if time.monotonic() > deadline or self.driver.poll() is not None:
                    self.close()
                    raise RuntimeError(f"{CHROMEDRIVER} did not start on port {port}")
                time.sleep(0.1)
        args = QUIET + [f"--user-data-dir={self.profile}/profile"] + ([WEBGPU] if webgpu else [])
        caps = {"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {"binary": CHROMIUM, "args": args},
        }}}
        try:
            self.session = self.call("POST", "/session", caps)["sessionId"]
            self.call("POST", self.path("/timeouts"), {"script": SCRIPT_TIMEOUT_S * 1000, "pageLoad": 120_000})
        except Exception:
            self.close()
            raise

    def path(self, suffix):
        return f"/session/{self.session}{suffix}"

    def call(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.base + path, data=data, method=method,
                                         headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(request, timeout=SCRIPT_TIMEOUT_S + 60) as response:
                return json.load(response)["value"]
        except urllib.error.HTTPError as e:
            value = json.load(e).get("value", {})
            raise WebDriverError(f"{method} {path}: {value.get('error')}: {value.get('message')}") from None

    def open(self, url):
        self.call("POST", self.path("/url"), {"url": url})

    def run(self, script, *args):
        """`script`'s value (a function body's return)."""
        return self.call("POST", self.path("/execute/sync"), {"script": script, "args": list(args)})

    def run_async(self, script, *args):
        """An async function body's result: `script` may await; what it
        returns comes back, what it throws is raised as a WebDriverError."""
        wrapped = ("const done = arguments[arguments.length - 1];"
                   f"(async (...args) => {{ {script} }})(...Array.from(arguments).slice(0, -1))"
                   ".then(v => done({ok: v}), e => done({error: String(e && e.message || e)}));")
        answer = self.call("POST", self.path("/execute/async"), {"script": wrapped, "args": list(args)})
        if "error" in answer:
            raise WebDriverError(answer["error"])
        return answer.get("ok")

    def element(self, css):
        found = self.call("POST", self.path("/element"), {"using": "css selector", "value": css})
        return next(iter(found.values()))

    def send_keys(self, css, text):
        self.call("POST", self.path(f"/element/{self.element(css)}/value"), {"text": text})

    def wait_for(self, script, timeout_s, what):
        """Polls `script` (a function body) until its value is truthy."""
        deadline = time.monotonic() + timeout_s
        while True:
            value = self.run(script)
            if value:
                return value
            if time.monotonic() > deadline:
                raise AssertionError(f"{what}: not within {timeout_s} s")
            time.sleep(0.25)

    def close(self):
        if self.session:
            try:
                self.call("DELETE", self.path(""))
            except Exception:
                pass
        self.driver.terminate()
        self.driver.wait(30)
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)


class WebDriverError(Exception):
    pass


# window.lambert is set by a module script: awaited once it exists.
AWAIT_READY = """
while (!window.lambert) await new Promise(r => setTimeout(r, 50));
await window.lambert.ready;
return window.lambert.adapter;
"""

# renderModel's pixels come back as base64 of the Float32Array's bytes
# (WebDriver has no typed arrays).
RENDER = """
const [b64, name, options] = args;
const bytes = Uint8Array.from(atob(b64), c => c.charCodeAt(0));
const image = await window.lambert.renderModel(bytes, name, options);
const raw = new Uint8Array(image.pixels.buffer, image.pixels.byteOffset, image.pixels.byteLength);
let text = "";
for (let i = 0; i < raw.length; i += 0x8000) text += String.fromCharCode(...raw.subarray(i, i + 0x8000));
return {width: image.width, height: image.height, pixels: btoa(text)};
"""


def render_in_page(browser, data, name, **options):
    """window.lambert.renderModel of `data`: (height, width, 3) floats."""
    image = browser.run_async(RENDER, base64.b64encode(data).decode(), name, options)
    pixels = np.frombuffer(base64.b64decode(image["pixels"]), dtype="<f4")
    w, h = image["width"], image["height"]
    assert pixels.size == w * h * 3, f"{pixels.size} floats for {w}×{h} RGB"
    return pixels.reshape(h, w, 3)


def read_pfm(path):
    """A PFM lambert wrote (little-endian, rows bottom to top), rows top to
    bottom: (height, width, 3) floats."""
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = (int(x) for x in f.readline().split())
        assert float(f.readline()) < 0, "lambert writes little-endian PFM"
        data = np.frombuffer(f.read(), dtype="<f4")
    return data.reshape(h, w, 3)[::-1]
