// SPDX-License-Identifier: GPL-3.0-or-later
#include "report/detail/page.h"

namespace pointsurf::detail {
namespace {

// Hooks for the browser test (tests/report/browser_check.py): window.pointsurfReady turns true
// after the first frame of the 3D view; window.pointsurfView.orbit(deg) turns the camera about
// the vertical axis and draws; window.pointsurfView.frames counts frames drawn.
const char* kPage = R"PAGE(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>pointsurf report: {{TITLE}}</title>
<style>
body { font: 14px/1.45 "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; margin: 0; color: #1d232b; background: #f4f5f7; }
header { background: #1f2a37; color: #fff; padding: 14px 24px; }
header h1 { margin: 0; font-size: 20px; font-weight: 600; }
header p { margin: 4px 0 0; color: #c9d2dc; }
nav { padding: 6px 24px; background: #e6e9ee; }
nav a { margin-right: 16px; color: #28507a; text-decoration: none; }
section { background: #fff; margin: 16px 24px; padding: 12px 18px 18px; border-radius: 6px; box-shadow: 0 1px 3px rgba(0,0,0,.12); }
h2 { font-size: 17px; margin: 4px 0 10px; }
h4 { margin: 8px 0 4px; }
table { border-collapse: collapse; font-size: 13px; }
td, th { border-bottom: 1px solid #e3e6ea; padding: 3px 10px 3px 4px; text-align: left; vertical-align: top; }
th { background: #f0f2f5; }
td:last-child { font-variant-numeric: tabular-nums; word-break: break-all; }
.ok { color: #1d7a35; font-weight: 600; } .bad { color: #b3261e; font-weight: 600; }
#viewer { position: relative; width: 100%; height: 560px; background: #eef0f3; border-radius: 4px; overflow: hidden; }
#c3d { width: 100%; height: 100%; display: block; }
#legend3d { position: absolute; right: 12px; top: 12px; background: rgba(255,255,255,.85); padding: 6px 8px; border-radius: 4px; font-size: 12px; }
#legend3d .bar { width: 220px; height: 12px; border: 1px solid #555; }
#legend3d .ticks { display: flex; justify-content: space-between; }
#viewmsg { position: absolute; left: 12px; top: 12px; color: #b3261e; }
.controls { margin: 8px 0; } .controls label { margin-right: 14px; }
.pics { display: grid; grid-template-columns: repeat(auto-fill, minmax(380px, 1fr)); gap: 10px; }
figure { margin: 0; } figure img { width: 100%; border: 1px solid #d5d9de; } figcaption { font-size: 12px; color: #555; }
.charts { display: flex; flex-wrap: wrap; gap: 16px; } .chart { position: relative; height: 280px; flex: 1 1 420px; }
.two { display: flex; flex-wrap: wrap; gap: 24px; }
details.stage { margin: 6px 0; } details.stage summary { cursor: pointer; font-weight: 600; }
ul.warn li { color: #8a5a00; }
</style>
<script>{{THREE_JS}}</script>
<script>{{ORBIT_JS}}</script>
<script>{{CHART_JS}}</script>
</head>
<body>
<header><h1>pointsurf report</h1><p>{{TITLE}}</p></header>
<nav><a href="#summary">Summary</a><a href="#view3d">3D view</a><a href="#pictures">Pictures</a><a href="#deviation">Deviation</a><a href="#stages">Stages</a><a href="#details">Metrics and parameters</a><a href="#warnings">Warnings</a></nav>
<section id="summary"><h2>Summary</h2>{{SUMMARY}}<ul>{{NOTES}}</ul></section>
<section id="view3d"><h2>3D view</h2>
<div class="controls">
<label><input type="checkbox" id="show-mesh" checked> mesh ({{MESH_TRIANGLES}} triangles)</label>
<label><input type="checkbox" id="show-cloud"> cloud ({{CLOUD_POINTS}} points)</label>
<label><input type="checkbox" id="show-wire"> wireframe</label>
<button id="reset-view">reset view</button> <span style="color:#666">drag: orbit, wheel: zoom, right drag: pan</span>
</div>
<div id="viewer"><canvas id="c3d"></canvas><div id="legend3d"></div><div id="viewmsg"></div></div>
</section>
<section id="pictures"><h2>Pictures (pointsurf render)</h2><div class="pics">{{PICTURES}}</div></section>
<section id="deviation"><h2>Deviation</h2><div class="two"><div>{{DEVIATION_TABLE}}</div><div class="chart"><canvas id="histogram"></canvas></div></div></section>
<section id="stages"><h2>Stages: time and memory</h2>
<div class="charts"><div class="chart"><canvas id="time-chart"></canvas></div><div class="chart"><canvas id="memory-chart"></canvas></div></div>
<table><thead><tr><th>#</th><th>stage</th><th>inputs</th><th>seconds</th><th>peak MiB</th><th>rise MiB</th></tr></thead><tbody>{{STAGE_ROWS}}</tbody></table>
</section>
<section id="details"><h2>Metrics and parameters</h2>{{STAGE_DETAILS}}</section>
<section id="warnings"><h2>Warnings</h2>{{WARNINGS}}</section>
<script type="application/json" id="pointsurf-data">{{PAYLOAD}}</script>
<script>
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("pointsurf-data").textContent);
  window.pointsurfReady = false;
  function decode(text, Type) {
    var bin = atob(text), bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  // Charts.
  if (window.Chart) {
    var common = { animation: false, responsive: true, maintainAspectRatio: false };
    if (data.histogram) {
      new Chart(document.getElementById("histogram"), {
        type: "bar",
        data: { labels: data.histogram.centres.map(function (c) { return c.toPrecision(3); }),
                datasets: [{ label: "points per deviation bin", data: data.histogram.counts, backgroundColor: data.histogram.colors,
                             barPercentage: 1.0, categoryPercentage: 1.0 }] },
        options: Object.assign({ plugins: { title: { display: true, text: "Deviation histogram (cloud units)" } } }, common)
      });
    }
    var labels = data.stages.map(function (s) { return s.label; });
    // One bar a stage: a long pipeline gets a taller chart, not squeezed labels.
    document.getElementById("time-chart").parentNode.style.height = Math.max(280, 18 * labels.length + 90) + "px";
    new Chart(document.getElementById("time-chart"), {
      type: "bar",
      data: { labels: labels, datasets: [{ label: "seconds", data: data.stages.map(function (s) { return s.seconds; }), backgroundColor: "#4c78a8" }] },
      options: Object.assign({ indexAxis: "y", scales: { y: { ticks: { autoSkip: false } } },
                             plugins: { title: { display: true, text: "Time per stage (s)" } } }, common)
    });
    new Chart(document.getElementById("memory-chart"), {
      type: "bar",
      data: { labels: labels, datasets: [
        { label: "peak resident MiB at the end", data: data.stages.map(function (s) { return s.peak_rss_mb; }), backgroundColor: "#9ecae9" },
        { label: "rise during the stage MiB", data: data.stages.map(function (s) { return s.rss_rise_mb; }), backgroundColor: "#e45756" }] },
      options: Object.assign({ plugins: { title: { display: true, text: "Memory per stage (MiB)" } } }, common)
    });
  }

  // Legend of the 3D view.
  if (!data.legend) document.getElementById("legend3d").style.display = "none";
  if (data.legend) {
    var l = data.legend, el = document.getElementById("legend3d");
    el.innerHTML = "<div>" + l.field + (l.tolerance > 0 ? " (green: |d| &le; " + l.tolerance.toPrecision(3) + ")" : "") + "</div>" +
      "<div class=\"bar\" style=\"background: linear-gradient(to right, " + l.under + " 0 5%, " +
      l.stops.map(function (c, i) { return c + " " + (5 + 90 * i / (l.stops.length - 1)).toFixed(1) + "%"; }).join(", ") +
      ", " + l.over + " 95% 100%)\"></div>" +
      "<div class=\"ticks\"><span>&lt; " + l.min.toPrecision(3) + "</span><span>0</span><span>&gt; +" + l.max.toPrecision(3) + "</span></div>";
  }

  // The 3D view.
  var msg = document.getElementById("viewmsg");
  if (!window.THREE) { msg.textContent = "three.js did not load"; return; }
  var canvas = document.getElementById("c3d");
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({ canvas: canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    msg.textContent = "No WebGL in this browser: " + e.message;
    return;
  }
  var scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef0f3);
  var radius = Math.max(data.radius, 1e-9);
  var camera = new THREE.PerspectiveCamera(35, 1, radius * 0.01, radius * 100);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x777788, 0.55));
  var key = new THREE.DirectionalLight(0xffffff, 0.65);
  key.position.set(-1, 1, 2);
  camera.add(key);
  scene.add(camera);
  var meshObject = null, wireObject = null, cloudObject = null;
  if (data.mesh) {
    var g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(decode(data.mesh.positions, Float32Array), 3));
    g.setAttribute("color", new THREE.BufferAttribute(decode(data.mesh.colors, Uint8Array), 3, true));
    g.setIndex(new THREE.BufferAttribute(decode(data.mesh.indices, Uint32Array), 1));
    g.computeVertexNormals();
    meshObject = new THREE.Mesh(g, new THREE.MeshPhongMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide, shininess: 30, specular: 0x222222 }));
    scene.add(meshObject);
    wireObject = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ color: 0x1b2430, wireframe: true, transparent: true, opacity: 0.35 }));
    wireObject.visible = false;
    scene.add(wireObject);
  }
  if (data.cloud) {
    var pg = new THREE.BufferGeometry();
    pg.setAttribute("position", new THREE.BufferAttribute(decode(data.cloud.positions, Float32Array), 3));
    pg.setAttribute("color", new THREE.BufferAttribute(decode(data.cloud.colors, Uint8Array), 3, true));
    cloudObject = new THREE.Points(pg, new THREE.PointsMaterial({ size: 2.5, sizeAttenuation: false, vertexColors: THREE.VertexColors }));
    cloudObject.visible = !data.mesh;
    document.getElementById("show-cloud").checked = cloudObject.visible;
    scene.add(cloudObject);
  }
  if (!data.mesh) document.getElementById("show-mesh").disabled = true;
  if (!data.cloud) document.getElementById("show-cloud").disabled = true;

  var controls = new THREE.OrbitControls(camera, canvas);
  function home() {
    var d = radius / Math.sin(camera.fov * Math.PI / 360) * 0.8;
    camera.position.set(d * 0.6, -d * 0.6, d * 0.5);
    controls.target.set(0, 0, 0);
    controls.update();
  }
  var frames = 0;
  function draw() { renderer.render(scene, camera); frames++; }
  function resize() {
    var w = canvas.clientWidth, h = canvas.clientHeight;
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
    draw();
  }
  controls.addEventListener("change", draw);
  window.addEventListener("resize", resize);
  document.getElementById("show-mesh").addEventListener("change", function (e) { if (meshObject) meshObject.visible = e.target.checked; draw(); });
  document.getElementById("show-cloud").addEventListener("change", function (e) { if (cloudObject) cloudObject.visible = e.target.checked; draw(); });
  document.getElementById("show-wire").addEventListener("change", function (e) { if (wireObject) wireObject.visible = e.target.checked; draw(); });
  document.getElementById("reset-view").addEventListener("click", function () { home(); draw(); });
  home();
  resize();
  window.pointsurfView = {
    orbit: function (deg) {
      var a = deg * Math.PI / 180, p = camera.position.clone().sub(controls.target);
      camera.position.set(p.x * Math.cos(a) - p.y * Math.sin(a), p.x * Math.sin(a) + p.y * Math.cos(a), p.z).add(controls.target);
      controls.update();
      draw();
      return frames;
    },
    get frames() { return frames; }
  };
  requestAnimationFrame(function () { draw(); window.pointsurfReady = true; });
})();
</script>
</body>
</html>
)PAGE";

}  // namespace

std::string fill_page(const std::map<std::string, std::string>& slots) {
  const std::string page = kPage;
  std::string out;
  out.reserve(page.size() + 1024);
  std::size_t at = 0;
  while (true) {
    const std::size_t open = page.find("{{", at);
    if (open == std::string::npos) break;
    const std::size_t close = page.find("}}", open);
    if (close == std::string::npos) break;
    out.append(page, at, open - at);
    const std::string name = page.substr(open + 2, close - open - 2);
    const auto it = slots.find(name);
    if (it != slots.end()) {
      if (name.size() > 3 && name.compare(name.size() - 3, 3, "_JS") == 0) {
        std::string js = it->second;
        for (std::size_t k = 0; (k = js.find("</script", k)) != std::string::npos; k += 9) js.replace(k, 2, "<\\/");
        out += js;
      } else {
        out += it->second;
      }
    }
    at = close + 2;
  }
  out.append(page, at, std::string::npos);
  return out;
}

}  // namespace pointsurf::detail
