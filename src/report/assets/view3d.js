// The map and camera paths in 3D on a 2D canvas: drag to orbit, wheel to zoom, double-click to reset.
(function () {
  'use strict';
  const canvas = document.getElementById('view3d');
  const source = document.getElementById('view3d-data');
  if (!canvas || !source) return;
  const data = JSON.parse(source.textContent);
  const ctx = canvas.getContext('2d');
  const up = data.up, n = data.points.length / 3;
  // A basis with `up` as the third axis, so that orbiting turns about the world's up direction.
  const a = Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  const dot = (u, v) => u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  const cross = (u, v) => [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
  const norm = (u) => { const l = Math.hypot(u[0], u[1], u[2]); return [u[0] / l, u[1] / l, u[2] / l]; };
  const e1 = norm(cross(up, a)), e2 = cross(up, e1);
  const toLocal = (x, y, z) => [dot([x, y, z], e1), dot([x, y, z], e2), dot([x, y, z], up)];
  // Centre and size from the camera paths (the points may hold far outliers).
  let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (const p of data.paths) for (let i = 0; i < p.xyz.length; i += 3)
    for (let k = 0; k < 3; ++k) { lo[k] = Math.min(lo[k], p.xyz[i + k]); hi[k] = Math.max(hi[k], p.xyz[i + k]); }
  if (!isFinite(lo[0])) { lo = [-1, -1, -1]; hi = [1, 1, 1]; }
  // Centred between the camera path and the map's median point, taking in the paths and most of the map.
  const median = (k) => {
    const v = [];
    for (let i = 0; i < n; ++i) v.push(data.points[3 * i + k]);
    v.sort((u, w) => u - w);
    return v[n >> 1];
  };
  const centre = [0, 1, 2].map((k) => (n ? 0.5 * median(k) : 0) + (n ? 0.5 : 1) * (lo[k] + hi[k]) / 2);
  const dist = [];
  for (let i = 0; i < n; ++i)
    dist.push(Math.hypot(data.points[3 * i] - centre[0], data.points[3 * i + 1] - centre[1], data.points[3 * i + 2] - centre[2]));
  dist.sort((u, v) => u - v);
  let radius = n ? dist[Math.floor(0.8 * (n - 1))] : 0;
  for (const c of [lo, hi]) radius = Math.max(radius, Math.hypot(c[0] - centre[0], c[1] - centre[1], c[2] - centre[2]));
  radius = Math.max(radius, 1e-6);
  const initial = { yaw: 0.7, pitch: 0.45, zoom: 1 };
  let view = Object.assign({}, initial);
  function project(x, y, z) {
    const l = toLocal(x - centre[0], y - centre[1], z - centre[2]);
    const cy = Math.cos(view.yaw), sy = Math.sin(view.yaw), cp = Math.cos(view.pitch), sp = Math.sin(view.pitch);
    const xr = cy * l[0] - sy * l[1], yr = sy * l[0] + cy * l[1];
    const depth = cp * yr + sp * l[2], height = -sp * yr + cp * l[2];
    // A pinhole 3 radii from the centre at zoom 1, the radius filling 45 % of the canvas.
    const d = 3 * radius / view.zoom + depth;
    if (d <= 1e-3 * radius) return null;
    const f = 1.35 * Math.min(canvas.width, canvas.height);
    return [canvas.width / 2 + f * xr / d, canvas.height / 2 - f * height / d];
  }
  function draw() {
    ctx.fillStyle = '#111';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    let drawn = 0;
    for (let i = 0; i < n; ++i) {
      const q = project(data.points[3 * i], data.points[3 * i + 1], data.points[3 * i + 2]);
      if (!q || q[0] < 0 || q[1] < 0 || q[0] >= canvas.width || q[1] >= canvas.height) continue;
      const g = Math.round(90 + 165 * data.intensity[i]);
      ctx.fillStyle = 'rgb(' + g + ',' + g + ',' + g + ')';
      ctx.fillRect(q[0], q[1], 1.6, 1.6);
      ++drawn;
    }
    for (const p of data.paths) {
      ctx.strokeStyle = p.color;
      ctx.lineWidth = 2;
      ctx.beginPath();
      let pen = false;
      for (let i = 0; i < p.xyz.length; i += 3) {
        const q = project(p.xyz[i], p.xyz[i + 1], p.xyz[i + 2]);
        if (!q) { pen = false; continue; }
        if (pen) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]);
        pen = true;
      }
      ctx.stroke();
    }
    ctx.fillStyle = '#4fc3f7';
    for (let i = 0; i < data.keyframes.length; i += 3) {
      const q = project(data.keyframes[i], data.keyframes[i + 1], data.keyframes[i + 2]);
      if (q) ctx.fillRect(q[0] - 2.5, q[1] - 2.5, 5, 5);
    }
    canvas.dataset.pointsDrawn = String(drawn);
  }
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointerup', () => { drag = null; });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    view.yaw += (e.clientX - drag[0]) * 0.01;
    view.pitch = Math.max(-1.5, Math.min(1.5, view.pitch + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    draw();
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    view.zoom = Math.max(0.2, Math.min(20, view.zoom * Math.exp(-e.deltaY * 0.001)));
    draw();
  }, { passive: false });
  canvas.addEventListener('dblclick', () => { view = Object.assign({}, initial); draw(); });
  draw();
})();
