// assist3d view: draws the points of the page's "view-data" JSON with plotly.js (inlined above).
// State: the colouring (rgb, instance, class, prediction), ground truth and prediction side by side
// or not, the point size. Every change redraws with Plotly.react; window.assist3dView exposes the
// state and a count of finished draws for scripted checks.
(function () {
  "use strict";
  var t0 = performance.now();
  var D = JSON.parse(document.getElementById("view-data").textContent);
  var N = D.n;

  function decode(s, Type) {
    if (s === null) return null;
    var bin = atob(s), bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  var X = decode(D.x, Float32Array), Y = decode(D.y, Float32Array), Z = decode(D.z, Float32Array);
  var RGB = decode(D.rgb, Uint8Array), INST = decode(D.instance, Int32Array);
  var KLASS = decode(D.klass, Int32Array), PRED = decode(D.pred, Int32Array);
  var HAVE = { rgb: !!RGB, instance: !!INST, "class": !!KLASS, prediction: !!PRED };
  var WHY = { rgb: "this input has no colours", instance: "this input has no ground-truth instances",
              "class": "this input has no classes", prediction: "no prediction given (assist3d view SCAN --pred FILE.npz)" };
  var SOURCE = { instance: INST, "class": KLASS, prediction: PRED };

  var state = { color: D.color, side: !!D.sideBySide, size: D.pointSize };
  var cache = {};

  var HEX = [];
  for (var h = 0; h < 256; h++) HEX.push((h < 16 ? "0" : "") + h.toString(16));

  function colors(mode) {
    if (cache[mode]) return cache[mode];
    var out = new Array(N), i;
    if (mode === "rgb") {
      for (i = 0; i < N; i++) out[i] = "#" + HEX[RGB[3 * i]] + HEX[RGB[3 * i + 1]] + HEX[RGB[3 * i + 2]];
    } else {
      var lab = SOURCE[mode], pal = D.palette, bg = D.background;
      for (i = 0; i < N; i++) { var v = lab[i]; out[i] = v >= 0 ? pal[v % pal.length] : bg; }
    }
    cache[mode] = out;
    return out;
  }

  function className(k) {
    if (k < 0) return "no class";
    return k < D.classNames.length ? D.classNames[k] : "class " + k;
  }

  // hover: plotly reports the point under the mouse, the page writes its own label (a text array of
  // N strings on the trace would cost plotly several seconds at 300k points)
  function describe(i) {
    var parts = [];
    if (INST) parts.push(INST[i] >= 0 ? "instance " + INST[i] : "background (no instance)");
    if (KLASS) parts.push("class: " + className(KLASS[i]));
    if (PRED) {
      var p = PRED[i];
      var sc = D.predScores && p >= 0 && p < D.predScores.length ? ", score " + D.predScores[p].toFixed(3) : "";
      parts.push(p >= 0 ? "predicted instance " + p + sc : "no predicted instance");
    }
    if (!parts.length) parts.push("point " + i);
    return parts;
  }

  function trace(mode, scene) {
    return {
      type: "scatter3d", mode: "markers", scene: scene, x: X, y: Y, z: Z,
      marker: { size: state.size, color: colors(mode), line: { width: 0 } },
      hoverinfo: "none", showlegend: false, name: mode
    };
  }

  var AXIS = { showbackground: false, showspikes: false, zeroline: false, color: "#888" };
  function sceneLayout(domain, camera) {
    var s = { domain: { x: domain, y: [0, 1] }, aspectmode: "data", dragmode: "turntable", uirevision: "keep",
              xaxis: Object.assign({ title: { text: "x (m)" } }, AXIS),
              yaxis: Object.assign({ title: { text: "y (m)" } }, AXIS),
              zaxis: Object.assign({ title: { text: "z (m)" } }, AXIS) };
    if (camera) s.camera = camera;
    return s;
  }

  var gd = document.getElementById("plot");
  var api = window.assist3dView = { state: state, draws: 0, ready: false, errors: [],
                                    timings: { decodeMs: performance.now() - t0, drawMs: [] } };

  function currentCamera() {
    var sc = gd.layout && gd.layout.scene;
    return sc && sc.camera ? JSON.parse(JSON.stringify(sc.camera)) : { eye: { x: 1.25, y: -1.25, z: 1.1 } };
  }

  function draw() {
    var start = performance.now();
    var camera = gd.layout ? currentCamera() : { eye: { x: 1.25, y: -1.25, z: 1.1 } };
    var data, layout = { margin: { l: 0, r: 0, t: 0, b: 0 }, paper_bgcolor: "#fff", uirevision: "keep" };
    if (state.side) {
      var left = state.color === "prediction" || state.color === "rgb" && !RGB ? "instance" : state.color;
      data = [trace(left, "scene"), trace("prediction", "scene2")];
      layout.scene = sceneLayout([0, 0.495], camera);
      layout.scene2 = sceneLayout([0.505, 1], camera);
    } else {
      data = [trace(state.color, "scene")];
      layout.scene = sceneLayout([0, 1], camera);
    }
    document.getElementById("titles").className = state.side ? "on" : "";
    syncControls();
    return Plotly.react(gd, data, layout, { displaylogo: false, responsive: true, scrollZoom: true })
      .then(function () { api.timings.drawMs.push(Math.round(performance.now() - start)); api.draws += 1; });
  }

  function syncControls() {
    var buttons = document.querySelectorAll("#bar button[data-color]");
    for (var i = 0; i < buttons.length; i++) {
      var b = buttons[i], mode = b.getAttribute("data-color");
      b.disabled = !HAVE[mode];
      b.title = HAVE[mode] ? "colour the points by " + mode : WHY[mode];
      b.setAttribute("aria-pressed", String(mode === state.color));
    }
    var side = document.getElementById("side");
    side.checked = state.side;
    side.disabled = !(INST && PRED);
    side.parentNode.title = side.disabled ? "needs ground-truth instances and a prediction" : "";
    document.getElementById("size").value = String(state.size);
  }

  // camera of one scene follows the other while side by side
  var syncing = false;
  function followCamera(ev) {
    if (!state.side || syncing || !ev) return;
    var from = ev["scene.camera"] ? "scene" : ev["scene2.camera"] ? "scene2" : null;
    if (!from) return;
    var upd = {};
    upd[from === "scene" ? "scene2.camera" : "scene.camera"] = ev[from + ".camera"];
    syncing = true;
    Plotly.relayout(gd, upd).then(function () { syncing = false; }, function () { syncing = false; });
  }

  api.setColor = function (mode) {
    if (!HAVE[mode]) return Promise.reject(new Error(WHY[mode]));
    state.color = mode;
    return draw();
  };
  api.setSideBySide = function (on) {
    state.side = !!on && !!(INST && PRED);
    return draw();
  };

  document.getElementById("name").textContent = D.name;
  document.getElementById("notes").textContent = D.notes.concat([N.toLocaleString("en") + " points; drag to turn, " +
    "scroll to zoom, right-drag to pan, hover a point for its instance and class"]).join(" \u00b7 ");
  var buttons = document.querySelectorAll("#bar button[data-color]");
  for (var i = 0; i < buttons.length; i++) {
    buttons[i].addEventListener("click", function (e) { api.setColor(e.currentTarget.getAttribute("data-color")); });
  }
  document.getElementById("side").addEventListener("change", function (e) { api.setSideBySide(e.target.checked); });
  document.getElementById("size").addEventListener("change", function (e) {
    state.size = parseFloat(e.target.value);
    draw();
  });

  var tip = document.getElementById("tip"), mouse = { x: 0, y: 0 };
  gd.addEventListener("mousemove", function (e) { mouse.x = e.clientX; mouse.y = e.clientY; }, true);
  function showTip(ev) {
    var pt = ev && ev.points && ev.points[0];
    if (!pt || typeof pt.pointNumber !== "number") return;
    tip.textContent = "";
    describe(pt.pointNumber).forEach(function (line) {
      var div = document.createElement("div");
      div.textContent = line;
      tip.appendChild(div);
    });
    tip.style.left = (mouse.x + 14) + "px";
    tip.style.top = (mouse.y + 14) + "px";
    tip.style.display = "block";
    api.hovered = pt.pointNumber;
  }
  function hideTip() { tip.style.display = "none"; }

  var status = document.getElementById("status");
  status.textContent = "drawing\u2026";
  draw().then(function () {
    gd.on("plotly_relayout", followCamera);
    gd.on("plotly_hover", showTip);
    gd.on("plotly_unhover", hideTip);
    status.textContent = "";
    api.ready = true;
  }, function (err) {
    status.textContent = "could not draw: " + err;
    api.errors.push(String(err));
  });
})();
