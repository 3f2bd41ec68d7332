// limpid ellipsoid viewer: orthographic 3-D view of impedance ellipsoids at
// their start points (Artemiadis et al. 2010, Fig. 4, Patel et al. 2013, Fig. 5). Written for limpid;
// no library. Drag to rotate; buttons pick the matrix kind.
(function () {
  "use strict";
  var holder = document.getElementById("ellipsoid-view");
  if (!holder) { return; }
  var data = JSON.parse(document.getElementById("ellipsoid-data").textContent);
  var NS = "http://www.w3.org/2000/svg";
  // as wide as the page; the drawing scales with it (viewBox)
  var W = Math.max(640, Math.min(1360, holder.clientWidth || 1200)), H = Math.round(0.5 * W);
  var svg = document.createElementNS(NS, "svg");
  svg.setAttribute("width", "100%");
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
      t.setAttribute("font-size", "13");
      t.textContent = name + " (m)";
      svg.appendChild(t);
    });
    var count = data.ellipsoids.filter(function (e) { return shown[e.kind]; }).length;
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
      // the name on hover (always when few are shown), and a tooltip with the principal values
      var label = document.createElementNS(NS, "text");
      var at = screen(e.centre);
      label.setAttribute("x", at[0] + 6); label.setAttribute("y", at[1] - 6);
      label.setAttribute("font-size", "13");
      label.setAttribute("class", "label");
      label.textContent = e.point;
      if (count > 8) { label.setAttribute("visibility", "hidden"); }
      g.appendChild(label);
      var tip = document.createElementNS(NS, "title");
      tip.textContent = e.point + " (" + e.kind + "): principal values " +
        e.eigenvalues.map(function (v) { return Number(v.toPrecision(4)); }).join(", ") + " " + data.units[e.kind];
      g.appendChild(tip);
      g.addEventListener("mouseenter", function () { label.setAttribute("visibility", "visible"); });
      g.addEventListener("mouseleave", function () { if (count > 8) { label.setAttribute("visibility", "hidden"); } });
      svg.appendChild(g);
    });
    // scale bars: a radius of `scale_value` in each shown kind, and a length in the lab
    var sc = 0.8 * Math.min(W, H) / span, row = 0;
    function bar(len, text, color, cls) {
      var y = H - 24 - 26 * row, g = document.createElementNS(NS, "g");
      g.setAttribute("class", cls);
      g.appendChild(path("M24," + (y - 5) + " L24," + (y + 5) + " M24," + y + " L" + (24 + len).toFixed(1) + "," + y +
        " M" + (24 + len).toFixed(1) + "," + (y - 5) + " L" + (24 + len).toFixed(1) + "," + (y + 5), "bar", color, 2));
      var t = document.createElementNS(NS, "text");
      t.setAttribute("x", 32 + len); t.setAttribute("y", y + 5); t.setAttribute("font-size", "13");
      t.textContent = text;
      g.appendChild(t);
      svg.appendChild(g);
      row += 1;
    }
    data.kinds.forEach(function (k) {
      if (!shown[k]) { return; }
      bar(data.scale_value[k] * data.scale[k] * sc, k + ": " + data.scale_value[k] + " " + data.units[k] + " (radius)", data.colors[k], "scale-bar");
    });
    bar(data.length_value * sc, "position: " + data.length_value + " m", "#666", "length-bar");
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
