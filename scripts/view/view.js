// mrslam_view's page: draws a run (live from /events, or replayed from /steps) on a canvas, in
// the world frame W or in any robot's own frame G_i. Estimates arrive in each robot's frame
// G_i, the truth in W; the header gives every frame's pose in W. The state drawn is on
// window.mrslamView (read by the browser test).
'use strict';

const COLORS = ['#d62728', '#1f77b4', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf'];
const ROBOT_RADIUS_PX = 6;

const view = { mode: null, header: null, step: null, frame: 'world', drawn: {}, ended: false };
window.mrslamView = view;
const records = new Map();  // step -> the step's record (evaluator::ViewStep)

// ---- SE(2): [x, y, heading] ---------------------------------------------------------------
function compose(a, b) {
  const c = Math.cos(a[2]), s = Math.sin(a[2]);
  return [a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]];
}
function inverse(a) {
  const c = Math.cos(a[2]), s = Math.sin(a[2]);
  return [-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]];
}
function frameOf(id) { return view.header.robots.find((r) => r.id === id).frame; }
// T(D <- W): the display frame D is W or a robot's G_j.
function displayFromWorld() { return view.frame === 'world' ? [0, 0, 0] : inverse(frameOf(view.frame)); }
// T(D <- G_i) = T(D <- W) * T(W <- G_i).
function displayFromRobot(id) { return compose(displayFromWorld(), frameOf(id)); }
function colorOf(id) { return COLORS[view.header.robots.findIndex((r) => r.id === id) % COLORS.length]; }
function sortedSteps() { return [...records.keys()].sort((a, b) => a - b); }

// ---- what is drawn, in the display frame ------------------------------------------------
function truthPose(rec, id) {
  const p = rec.truth && rec.truth.robots[id];
  return p ? compose(displayFromWorld(), p) : null;
}
function estimatePose(rec, id) {
  const e = rec.estimates[id];
  return e ? compose(displayFromRobot(id), e.pose) : null;
}
// Every point that may be drawn over the whole run, so the scale holds still while it plays.
function bounds() {
  const b = { minX: Infinity, minY: Infinity, maxX: -Infinity, maxY: -Infinity };
  const add = (p) => {
    b.minX = Math.min(b.minX, p[0]); b.maxX = Math.max(b.maxX, p[0]);
    b.minY = Math.min(b.minY, p[1]); b.maxY = Math.max(b.maxY, p[1]);
  };
  const w = displayFromWorld();
  for (const rec of records.values()) {
    for (const r of view.header.robots) {
      for (const p of [truthPose(rec, r.id), estimatePose(rec, r.id)]) if (p) add(p);
    }
    if (rec.truth) for (const l of rec.truth.landmarks) add(compose(w, [l[1], l[2], 0]));
  }
  if (!isFinite(b.minX)) return { minX: -5, minY: -5, maxX: 5, maxY: 5 };
  return b;
}
function projection(canvas) {
  const b = bounds();
  const margin = 30;
  const spanX = Math.max(b.maxX - b.minX, 1), spanY = Math.max(b.maxY - b.minY, 1);
  const scale = Math.min((canvas.width - 2 * margin) / spanX, (canvas.height - 2 * margin) / spanY);
  const cx = (b.minX + b.maxX) / 2, cy = (b.minY + b.maxY) / 2;
  const toPx = (p) => [canvas.width / 2 + (p[0] - cx) * scale, canvas.height / 2 - (p[1] - cy) * scale];
  return { scale, toPx };
}

// ---- drawing -------------------------------------------------------------------------------
// The half axes (standard deviations) of a 2x2 covariance [xx, xy, yy, ...], major first, and
// the major axis's angle.
function axes(cov) {
  const [a, b, c] = cov;
  const mean = (a + c) / 2, diff = Math.sqrt(((a - c) / 2) ** 2 + b * b);
  return [Math.sqrt(Math.max(mean + diff, 0)), Math.sqrt(Math.max(mean - diff, 0)), 0.5 * Math.atan2(2 * b, a - c)];
}
function twoSigmaMajor(cov) { return 2 * axes(cov)[0]; }
// 2-sigma ellipse of a 2x2 covariance [xx, xy, yy] given in a frame rotated by `rotation` in D.
function drawEllipse(ctx, proj, center, cov, rotation, color) {
  const [major, minor, angle] = axes(cov);
  const [px, py] = proj.toPx(center);
  ctx.beginPath();
  ctx.ellipse(px, py, 2 * major * proj.scale + 0.5, 2 * minor * proj.scale + 0.5, -(angle + rotation), 0, 2 * Math.PI);
  ctx.strokeStyle = color;
  ctx.lineWidth = 1;
  ctx.stroke();
}
function drawPath(ctx, proj, points, color, dashed) {
  if (points.length < 2) return;
  ctx.beginPath();
  points.forEach((p, i) => { const [x, y] = proj.toPx(p); if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y); });
  ctx.setLineDash(dashed ? [5, 4] : []);
  ctx.strokeStyle = color;
  ctx.lineWidth = dashed ? 1 : 1.5;
  ctx.stroke();
  ctx.setLineDash([]);
}
function drawTrueLandmarks(ctx, proj, rec) {
  if (!rec.truth) return;
  const w = displayFromWorld();
  for (const [, x, y, moving] of rec.truth.landmarks) {
    const [px, py] = proj.toPx(compose(w, [x, y, 0]));
    ctx.fillStyle = ctx.strokeStyle = '#111';
    if (moving) ctx.strokeRect(px - 4, py - 4, 8, 8); else ctx.fillRect(px - 4, py - 4, 8, 8);
  }
}
function drawMap(ctx, proj, id, estimate) {
  const t = displayFromRobot(id), color = colorOf(id);
  for (const [x, y, cxx, cxy, cyy, moving, heading, v] of estimate.landmarks) {
    const p = compose(t, [x, y, heading]);
    drawEllipse(ctx, proj, p, [cxx, cxy, cyy], t[2], color);
    const [px, py] = proj.toPx(p);
    ctx.beginPath();
    ctx.arc(px, py, 3, 0, 2 * Math.PI);
    ctx.fillStyle = color;
    ctx.fill();
    if (moving && v > 0) drawPath(ctx, proj, [p, compose(p, [v, 0, 0])], color, false);
  }
}
function drawLidar(ctx, proj, rec, id) {
  const rays = rec.lidar && rec.lidar[id], pose = truthPose(rec, id);
  if (!rays || !pose) return;
  ctx.globalAlpha = 0.3;
  for (const [range, bearing] of rays) {
    drawPath(ctx, proj, [pose, compose(pose, [range * Math.cos(bearing), range * Math.sin(bearing), 0])], colorOf(id));
  }
  ctx.globalAlpha = 1;
}
function drawTruePose(ctx, proj, pose, color) {
  const [px, py] = proj.toPx(pose);
  const tip = (angle, r) => [px + r * Math.cos(pose[2] + angle), py - r * Math.sin(pose[2] + angle)];
  ctx.beginPath();
  ctx.moveTo(...tip(0, 11));
  ctx.lineTo(...tip(2.5, 8));
  ctx.lineTo(...tip(-2.5, 8));
  ctx.closePath();
  ctx.strokeStyle = color;
  ctx.lineWidth = 2;
  ctx.stroke();
}
function drawEstimatePose(ctx, proj, pose, color) {
  const [px, py] = proj.toPx(pose);
  ctx.beginPath();
  ctx.moveTo(px, py);
  ctx.lineTo(px + 14 * Math.cos(pose[2]), py - 14 * Math.sin(pose[2]));
  ctx.strokeStyle = color;
  ctx.lineWidth = 2;
  ctx.stroke();
  ctx.beginPath();
  ctx.arc(px, py, ROBOT_RADIUS_PX, 0, 2 * Math.PI);
  ctx.fillStyle = color;
  ctx.fill();
}

// The records up to the shown step, in step order.
function recordsUpTo(step) { return sortedSteps().filter((s) => s <= step).map((s) => records.get(s)); }

// A robot's paths, true pose and estimate ellipse; its estimate's disc comes last (drawDisc), so
// that nothing covers it.
function drawRobot(ctx, proj, rec, past, id) {
  const color = colorOf(id), estimate = rec.estimates[id];
  drawPath(ctx, proj, past.map((r) => truthPose(r, id)).filter((p) => p), color, true);
  drawPath(ctx, proj, past.map((r) => estimatePose(r, id)).filter((p) => p), color, false);
  const drawn = {};
  const truth = truthPose(rec, id);
  if (truth) {
    drawTruePose(ctx, proj, truth, color);
    const [px, py] = proj.toPx(truth);
    drawn.truth = { x: truth[0], y: truth[1], heading: truth[2], px, py };
  }
  if (estimate) {
    const pose = estimatePose(rec, id);
    drawEllipse(ctx, proj, pose, estimate.cov, displayFromRobot(id)[2], color);
    const [px, py] = proj.toPx(pose);
    drawn.estimate = { x: pose[0], y: pose[1], heading: pose[2], px, py, step: estimate.step };
  }
  return drawn;
}
function drawDisc(ctx, proj, rec, id) {
  if (rec.estimates[id]) drawEstimatePose(ctx, proj, estimatePose(rec, id), colorOf(id));
}

function renderMap(rec) {
  const canvas = document.getElementById('map');
  if (canvas.width !== canvas.clientWidth || canvas.height !== canvas.clientHeight) {
    canvas.width = canvas.clientWidth;
    canvas.height = canvas.clientHeight;
  }
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const proj = projection(canvas);
  const past = recordsUpTo(rec.step);
  drawTrueLandmarks(ctx, proj, rec);
  for (const { id } of view.header.robots) {
    if (rec.estimates[id]) drawMap(ctx, proj, id, rec.estimates[id]);
    drawLidar(ctx, proj, rec, id);
  }
  view.drawn = {};
  for (const { id } of view.header.robots) view.drawn[id] = drawRobot(ctx, proj, rec, past, id);
  for (const { id } of view.header.robots) drawDisc(ctx, proj, rec, id);
}

// ---- the panels: position error over time, estimator CPU, rejected samples, frames, rendezvous
// Position error per step of the robot's estimate against the truth in its own frame G_i.
function errorSeries(id, past) {
  const truthByStep = new Map(), series = [];
  const own = inverse(frameOf(id));
  for (const r of past) if (r.truth && r.truth.robots[id]) truthByStep.set(r.truth.step, compose(own, r.truth.robots[id]));
  for (const r of past) {
    const e = r.estimates[id], t = e && truthByStep.get(e.step);
    if (t) series.push([e.step, Math.hypot(e.pose[0] - t[0], e.pose[1] - t[1])]);
  }
  return series;
}
function drawSparkline(canvas, series, color) {
  canvas.width = canvas.clientWidth;
  canvas.height = canvas.clientHeight;
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const steps = view.header.steps || 1, top = Math.max(0.1, ...series.map((s) => s[1]));
  ctx.beginPath();
  series.forEach(([step, err], i) => {
    const x = (step / steps) * canvas.width, y = canvas.height - 2 - (err / top) * (canvas.height - 14);
    if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
  });
  ctx.strokeStyle = color;
  ctx.stroke();
  ctx.fillStyle = '#555';
  ctx.fillText(`max ${top.toFixed(2)} m`, 2, 10);
}
function panelOf(id) {
  let panel = document.getElementById(`panel-${id}`);
  if (panel) return panel;
  panel = document.createElement('div');
  panel.className = 'panel';
  panel.id = `panel-${id}`;
  panel.style.setProperty('--color', colorOf(id));
  panel.innerHTML = `<h3>${id}</h3><p class="error"></p><canvas></canvas><p class="cpu"></p><p class="rejected"></p>` +
    '<p class="frames"></p><p class="rendezvous"></p>';
  document.getElementById('panels').appendChild(panel);
  return panel;
}
function renderPanels(rec) {
  const past = recordsUpTo(rec.step);
  for (const { id } of view.header.robots) {
    const panel = panelOf(id), e = rec.estimates[id], series = errorSeries(id, past);
    const last = series.length ? series[series.length - 1][1] : null;
    const sigma = e ? twoSigmaMajor(e.cov) : null;
    panel.querySelector('.error').textContent =
      last === null ? 'position error -' : `position error ${last.toFixed(3)} m (2-sigma up to ${sigma.toFixed(3)} m)`;
    drawSparkline(panel.querySelector('canvas'), series, colorOf(id));
    panel.querySelector('.cpu').textContent = `estimator CPU this step ${e ? e.cpu_ms.toFixed(2) : '-'} ms`;
    panel.querySelector('.rejected').textContent = `rejected samples ${e ? e.rejected : '-'}`;
    panel.querySelector('.frames').textContent = `frames known: ${e && e.frames_known.length ? e.frames_known.join(', ') : 'none'}`;
    panel.querySelector('.rendezvous').textContent =
      `rendezvous: ${e && e.rendezvous.length ? e.rendezvous.map(([peer, s]) => `${peer} at step ${s}`).join(', ') : 'none'}`;
    if (view.drawn[id]) view.drawn[id].error_m = last;
  }
}

function render() {
  const rec = records.get(view.step);
  if (!rec) return;
  document.getElementById('step').textContent = String(rec.step);
  renderMap(rec);
  renderPanels(rec);
}

// ---- data: live (Server-Sent Events) or replay ---------------------------------------------
function setStatus(text) { document.getElementById('status').textContent = text; }

// A live run's past frames keep only what the paths and error plots need (the poses), so that a
// long run does not fill the browser's memory with maps and scans.
function compact(rec) {
  delete rec.lidar;
  if (rec.truth) rec.truth.landmarks = [];
  for (const e of Object.values(rec.estimates)) e.landmarks = [];
}

function startLive() {
  const events = new EventSource('/events');
  events.onopen = () => setStatus('live');
  events.onmessage = (message) => {
    const rec = JSON.parse(message.data);
    if (records.has(view.step) && view.step !== rec.step) compact(records.get(view.step));
    records.set(rec.step, rec);
    view.step = rec.step;
    view.ended = rec.step >= view.header.steps;
    render();
  };
  events.onerror = () => {
    if (view.ended) {
      events.close();
      setStatus('run finished');
    } else {
      setStatus('disconnected, retrying');
    }
  };
}

async function startReplay() {
  const steps = await (await fetch('/steps')).json();
  for (const rec of steps) records.set(rec.step, rec);
  const all = sortedSteps();
  const slider = document.getElementById('slider');
  slider.min = String(all[0]);
  slider.max = String(all[all.length - 1]);
  slider.value = slider.max;
  document.getElementById('replay').hidden = false;
  slider.addEventListener('input', () => {
    view.step = all.reduce((best, s) => (s <= Number(slider.value) ? s : best), all[0]);
    render();
  });
  view.step = all[all.length - 1];
  setStatus('replay');
  render();
}

async function start() {
  const info = await (await fetch('/info')).json();
  view.mode = info.mode;
  view.header = info.header;
  document.getElementById('title').textContent = `${info.header.scenario} (seed ${info.header.seed})`;
  document.getElementById('steps').textContent = String(info.header.steps);
  const select = document.getElementById('frame');
  for (const { id } of info.header.robots) {
    const option = document.createElement('option');
    option.value = id;
    option.textContent = `${id}'s frame G_${id}`;
    select.appendChild(option);
  }
  select.addEventListener('change', () => { view.frame = select.value; render(); });
  window.addEventListener('resize', render);
  if (info.mode === 'live') startLive(); else await startReplay();
}

start().catch((error) => setStatus(`error: ${error}`));
