// limpid ellipsoid viewer: orthographic 3-D view of impedance ellipsoids at
// their start points (seed 000 Fig. 4, seed 001 Fig. 5). Written for limpid;
// no library. Drag to rotate; buttons pick the matrix kind.
(function () {
  "use strict";
  var holder = document.getElementById("ellipsoid-view");
  if (!holder) { return; }
  var data = JSON.parse(document.getElementById("ellipsoid-data").textContent);
  var NS = "http://www.w3.org/2000/svg";
  var W = 640, H = 480;
  var svg = document.createElementNS(NS, "svg");
  svg.setAttribute("width", W);
  svg.setAttribute("height", H);
  svg.setAttribute("viewBox", "0 0 " + W + " " + H);
  svg.setAttribute("class", "viewer");
  holder.appendChild(svg);
  var yaw = -0.6, pitch = 0.35;
  var shown = {};
  data.kinds.forEach(function (k) { shown[k] = (k === data.kinds[0]); });

  // rotate a lab point into view coordinates (x right, y up, z towards the viewer)
  function view(p) {
    var cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    var x1 = cy * p[0] - sy * p[1], y1 = sy * p[0] + cy * p[1], z1 = p[2];
    return [y1, cp * z1 - sp * x1, sp * z1 + cp * x1];
  }
  var centre = data.centre, span = data.span;
  function screen(p) {
    var q = view([p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]]);
    var s = 0.8 * Math.min(W, H) / span;
    return [W / 2 + s * q[0], H / 2 - s * q[1]];
  }
  function ring(c, a, b, n) {
    // points c + cos(t) a + sin(t) b
    var pts = [];
    for (var i = 0; i <= n; i++) {
      var t = 2 * Math.PI * i / n, ct = Math.cos(t), st = Math.sin(t);
      pts.push(screen([c[0] + ct * a[0] + st * b[0], c[1] + ct * a[1] + st * b[1], c[2] + ct * a[2] + st * b[2]]));
    }
    return "M" + pts.map(function (p) { return p[0].toFixed(1) + "," + p[1].toFixed(1); }).join(" L");
  }
  function path(d, cls, color, width) {
    var e = document.createElementNS(NS, "path");
    e.setAttribute("d", d);
    e.setAttribute("class", cls);
    e.setAttribute("fill", "none");
    e.setAttribute("stroke", color);
    e.setAttribute("stroke-width", width);
    return e;
  }
  function draw() {
    while (svg.firstChild) { svg.removeChild(svg.firstChild); }
    // lab axes from the workspace centre
    var axisLen = 0.35 * span;
    ["x", "y", "z"].forEach(function (name, i) {
      var end = centre.slice(); end[i] += axisLen;
      var a = screen(centre), b = screen(end);
      svg.appendChild(path("M" + a[0] + "," + a[1] + " L" + b[0] + "," + b[1], "axis", "#888", 1));
      var t = document.createElementNS(NS, "text");
      t.setAttribute("x", b[0] + 3); t.setAttribute("y", b[1] - 3);
      t.textContent = name;
      svg.appendChild(t);
    });
    data.ellipsoids.forEach(function (e) {
      if (!shown[e.kind]) { return; }
      var g = document.createElementNS(NS, "g");
      g.setAttribute("class", "ellipsoid");
      g.setAttribute("data-kind", e.kind);
      g.setAttribute("data-point", e.point);
      var s = data.scale[e.kind];
      var ax = [0, 1, 2].map(function (k) {
        var r = Math.abs(e.eigenvalues[k]) * s;
        return [e.axes[0][k] * r, e.axes[1][k] * r, e.axes[2][k] * r];
      });
      var color = data.colors[e.kind];
      // the three principal sections and two more rings for shape
      g.appendChild(path(ring(e.centre, ax[0], ax[1], 48), "section", color, 1.6));
      g.appendChild(path(ring(e.centre, ax[1], ax[2], 48), "section", color, 1.2));
      g.appendChild(path(ring(e.centre, ax[0], ax[2], 48), "section", color, 1.2));
      var label = document.createElementNS(NS, "text");
      var at = screen(e.centre);
      label.setAttribute("x", at[0] + 4); label.setAttribute("y", at[1] + 12);
      label.setAttribute("font-size", "11");
      label.textContent = e.point;
      g.appendChild(label);
      svg.appendChild(g);
    });
    // scale sphere: radius of `scale_value` in the shown kind
    data.kinds.forEach(function (k, i) {
      if (!shown[k]) { return; }
      var r = data.scale_value[k] * data.scale[k];
      var g = document.createElementNS(NS, "g");
      g.setAttribute("class", "scale-sphere");
      var sc = 0.8 * Math.min(W, H) / span;
      var e = document.createElementNS(NS, "circle");
      e.setAttribute("cx", 40); e.setAttribute("cy", H - 40 - 60 * i);
      e.setAttribute("r", Math.max(2, r * sc));
      e.setAttribute("fill", "none"); e.setAttribute("stroke", data.colors[k]); e.setAttribute("stroke-dasharray", "3 2");
      g.appendChild(e);
      var t = document.createElementNS(NS, "text");
      t.setAttribute("x", 40 + Math.max(2, r * sc) + 6); t.setAttribute("y", H - 36 - 60 * i);
      t.textContent = "sphere: " + data.scale_value[k] + " " + data.units[k];
      g.appendChild(t);
      svg.appendChild(g);
    });
  }
  var dragging = null;
  svg.addEventListener("mousedown", function (ev) { dragging = [ev.clientX, ev.clientY]; });
  window.addEventListener("mouseup", function () { dragging = null; });
  window.addEventListener("mousemove", function (ev) {
    if (!dragging) { return; }
    yaw += (ev.clientX - dragging[0]) * 0.01;
    pitch = Math.max(-1.5, Math.min(1.5, pitch + (ev.clientY - dragging[1]) * 0.01));
    dragging = [ev.clientX, ev.clientY];
    draw();
  });
  var buttons = document.getElementById("ellipsoid-kinds");
  data.kinds.forEach(function (k) {
    var b = document.createElement("button");
    b.textContent = k;
    b.setAttribute("data-kind", k);
    b.className = shown[k] ? "on" : "";
    b.addEventListener("click", function () {
      shown[k] = !shown[k];
      b.className = shown[k] ? "on" : "";
      draw();
    });
    buttons.appendChild(b);
  });
  // ?all in the address shows every kind (used by the browser test)
  if (window.location.search.indexOf("all") >= 0) {
    data.kinds.forEach(function (k) { shown[k] = true; });
  }
  draw();
})();
