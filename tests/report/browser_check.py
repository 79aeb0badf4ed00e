#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Opens a pointsurf HTML report in headless Chromium (software WebGL through SwiftShader),
driven over the DevTools protocol, and checks that it is a working 3D report:

  * the page sets window.pointsurfReady (the 3D view drew its first frame) within the timeout;
  * no console error, no uncaught exception, no failed load;
  * the 3D view's screenshot is not blank (a share of its pixels differs from the background);
  * after a scripted orbit of the camera (window.pointsurfView.orbit) the screenshot differs.

usage: browser_check.py REPORT.html [--out DIR] [--timeout S]   (POINTSURF_CHROMIUM: the browser to use)
Exit 0: all checks pass; 1: a check failed (said why); 77: Chromium cannot start here (said why).
Screenshots are written to DIR (default: beside the report) as view_before.png, view_after.png.
"""
import argparse
import base64
import json
import os
import re
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request
import zlib

SKIP = 77


def decode_png(data):
    """8-bit RGB or RGBA PNG, not interlaced (what Chromium writes) -> (width, height, rows of bytes, bytes per pixel)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour in (2, 6) and interlace == 0, "unexpected PNG layout"
            bpp = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, rows, bpp


def pixels(png):
    w, h, rows, bpp = decode_png(png)
    return w, h, [tuple(r[i:i + 3]) for r in rows for i in range(0, w * bpp, bpp)]


class WebSocket:
    """A minimal client (RFC 6455) over the standard library: text frames, client masking, enough
    for the DevTools protocol, so the check needs no package beyond Python."""

    def __init__(self, url, timeout):
        m = re.match(r"ws://([^:/]+):(\d+)(/.*)", url)
        self.sock = socket.create_connection((m.group(1), int(m.group(2))), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET {m.group(3)} HTTP/1.1\r\nHost: {m.group(1)}:{m.group(2)}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(1)
            if not chunk:
                raise RuntimeError("websocket: connection closed during the handshake")
            head += chunk
        if b" 101 " not in head.split(b"\r\n")[0]:
            raise RuntimeError(f"websocket: handshake refused: {head.splitlines()[0]!r}")

    def _exact(self, n):
        data = b""
        while len(data) < n:
            chunk = self.sock.recv(n - len(data))
            if not chunk:
                raise RuntimeError("websocket: connection closed")
            data += chunk
        return data

    def send(self, text):
        payload = text.encode()
        n = len(payload)
        head = bytes([0x81]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n) if n < 65536
                                else bytes([0x80 | 127]) + struct.pack(">Q", n))
        mask = os.urandom(4)
        self.sock.sendall(head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))

    def recv(self):
        message = b""
        while True:
            b0, b1 = self._exact(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._exact(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._exact(8))[0]
            data = self._exact(n)
            opcode = b0 & 0x0F
            if opcode == 0x8:
                raise RuntimeError("websocket: closed by the browser")
            if opcode in (0x9, 0xA):
                continue  # ping / pong
            message += data
            if b0 & 0x80:
                return message.decode()


class DevTools:
    def __init__(self, url, timeout):
        self.ws = WebSocket(url, timeout)
        self.next_id = 0
        self.events = []

    def call(self, method, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def evaluate(self, expression):
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression}: {r['exceptionDetails'].get('text')}")
        return r["result"].get("value")


def start_chromium(profile, timeout):
    exe = os.environ.get("POINTSURF_CHROMIUM") or shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if exe is None:
        return None, "no chromium on PATH (Debian package chromium)"
    if not os.access(exe, os.X_OK):
        return None, f"{exe} is not an executable"
    args = [exe, "--headless", "--no-sandbox", "--disable-gpu-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
            "--enable-webgl", "--ignore-gpu-blocklist", "--no-first-run", "--no-default-browser-check", "--disable-extensions",
            "--remote-debugging-port=0", "--remote-debugging-address=127.0.0.1", f"--user-data-dir={profile}",
            "--window-size=1280,1800", "about:blank"]
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + timeout
    lines = []
    while time.time() < deadline:
        line = proc.stderr.readline()
        if not line:
            if proc.poll() is not None:
                return None, f"chromium exited with {proc.returncode}: {' '.join(lines[-3:]).strip()}"
            continue
        lines.append(line)
        m = re.search(r"DevTools listening on (ws://\S+)", line)
        if m:
            return (proc, m.group(1)), None
    proc.kill()
    return None, f"chromium did not open its DevTools port within {timeout} s"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("report")
    ap.add_argument("--out")
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()
    report = os.path.abspath(a.report)
    out = a.out or os.path.dirname(report)
    os.makedirs(out, exist_ok=True)
    profile = tempfile.mkdtemp(prefix="pointsurf_chromium_")
    started, why = start_chromium(profile, 30)
    if started is None:
        print(f"SKIP: Chromium cannot start: {why}")
        shutil.rmtree(profile, ignore_errors=True)
        return SKIP
    proc, browser_ws = started
    failures = []
    try:
        port = re.search(r":(\d+)/", browser_ws).group(1)
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
        page = next(t for t in targets if t.get("type") == "page")
        dt = DevTools(page["webSocketDebuggerUrl"], a.timeout)
        for domain in ("Runtime", "Log", "Page"):
            dt.call(f"{domain}.enable")
        t0 = time.time()
        dt.call("Page.navigate", url="file://" + report)
        ready = False
        while time.time() - t0 < a.timeout:
            if dt.evaluate("window.pointsurfReady === true"):
                ready = True
                break
            time.sleep(0.2)
        load_s = time.time() - t0
        if not ready:
            message = dt.evaluate("(document.getElementById('viewmsg') || {}).textContent")
            failures.append(f"the 3D view did not become ready within {a.timeout} s (its message: {message!r})")
        rect = dt.evaluate("(function(){var e=document.getElementById('viewer');e.scrollIntoView();"
                           "var r=e.getBoundingClientRect();return [r.left+window.scrollX,r.top+window.scrollY,r.width,r.height];})()")
        clip = {"x": rect[0], "y": rect[1], "width": rect[2], "height": rect[3], "scale": 0.5}  # half size: quick to decode

        def shot(name):
            time.sleep(0.3)
            data = dt.call("Page.captureScreenshot", format="png", clip=clip, captureBeyondViewport=True)["data"]
            png = base64.b64decode(data)
            with open(os.path.join(out, name), "wb") as f:
                f.write(png)
            return pixels(png)

        w, h, before = shot("view_before.png")
        background = (238, 240, 243)  # #eef0f3, the scene's background
        covered = sum(1 for p in before if max(abs(p[k] - background[k]) for k in range(3)) > 12)
        share = covered / max(1, len(before))
        if share < 0.01:
            failures.append(f"the 3D view is blank: {share:.2%} of its {w}x{h} pixels differ from the background")
        frames_before = dt.evaluate("window.pointsurfView ? window.pointsurfView.frames : -1")
        dt.evaluate("window.pointsurfView.orbit(40)")
        _, _, after = shot("view_after.png")
        changed = sum(1 for p, q in zip(before, after) if max(abs(p[k] - q[k]) for k in range(3)) > 12) / max(1, len(before))
        if changed < 0.005:
            failures.append(f"the orbit changed only {changed:.2%} of the view's pixels: not a live 3D view")
        # Console errors, exceptions and failed loads seen at any time.
        for e in dt.events:
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.exceptionThrown":
                failures.append(f"uncaught exception: {p['exceptionDetails'].get('exception', {}).get('description') or p['exceptionDetails'].get('text')}")
            elif m == "Runtime.consoleAPICalled" and p.get("type") == "error":
                failures.append("console error: " + " ".join(str(x.get("value", x.get("description", ""))) for x in p.get("args", [])))
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                failures.append(f"log error: {p['entry'].get('text')}")
        size_mb = os.path.getsize(report) / 1e6
        print(json.dumps({"report": report, "report_mb": round(size_mb, 2), "ready_s": round(load_s, 2), "view": [w, h],
                          "covered_share": round(share, 4), "orbit_changed_share": round(changed, 4), "frames_before_orbit": frames_before}))
    except Exception as e:  # a broken page or protocol: a failure with its reason
        failures.append(f"{type(e).__name__}: {e}")
    finally:
        proc.kill()
        proc.wait()
        shutil.rmtree(profile, ignore_errors=True)
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
