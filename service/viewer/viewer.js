// sphereplan viewer: pick a map and robot, click (drag for heading) the start and goal, plan, simulate,
// reconfigure. Talks only to this server's /v1 API; no external resources.
"use strict";

const $ = (id) => document.getElementById(id);
const canvas = $("canvas");
const ctx = canvas.getContext("2d");
const MAX_W = 900, MAX_H = 700, FOOTPRINT_SPACING_M = 0.25;

const viewer = {
  ready: false, busy: false,
  map: null, info: null, image: null, robots: {},
  start: null, goal: null,
  plan: null, sim: null, rec: null, lastRequest: null, error: null, live: null,
  scale: 1,  // canvas px per cell
};
window.viewer = viewer;

function status(text) { $("status").textContent = text; $("status").title = text; }
const fmt = (v, unit, digits = 2) => (v === null || v === undefined ? "–" : `${Number(v).toFixed(digits)} ${unit}`);

async function api(method, path, body) {
  const response = await fetch(path, {
    method, headers: body ? { "content-type": "application/json" } : {},
    body: body ? JSON.stringify(body) : undefined,
  });
  const data = await response.json();
  if (!response.ok) {
    const where = data.field ? ` (${data.field})` : "";
    const error = new Error(`${response.status} ${data.error_code}: ${data.error_msg}${where}`);
    error.body = data;  // a failed plan or simulation still says what it did
    throw error;
  }
  return data;
}

// ------------------------------------------------------------------------------------ coordinates

function worldToCanvas(x, y) {
  const { resolution_m: res, origin, height } = viewer.info;
  return [((x - origin[0]) / res) * viewer.scale, (height - (y - origin[1]) / res) * viewer.scale];
}
function canvasToWorld(cx, cy) {
  const { resolution_m: res, origin, height } = viewer.info;
  return [origin[0] + (cx / viewer.scale) * res, origin[1] + (height - cy / viewer.scale) * res];
}
// page (CSS px, as mouse events and Playwright use) of a world point: what the browser test clicks
viewer.worldToPage = (x, y) => {
  const [cx, cy] = worldToCanvas(x, y);
  const r = canvas.getBoundingClientRect();
  return [r.left + cx * (r.width / canvas.width), r.top + cy * (r.height / canvas.height)];
};
viewer.worldToCanvas = worldToCanvas;
const pxPerM = () => viewer.scale / viewer.info.resolution_m;

// ------------------------------------------------------------------------------------ drawing

function rollColour(roll, maxRoll) {
  const u = maxRoll > 0 ? Math.max(-1, Math.min(1, roll / maxRoll)) : 0;
  const c = (v) => Math.round(255 * v);
  return `rgb(${c(Math.max(0, u))},${c(1 - Math.abs(u))},${c(Math.max(0, -u))})`;
}

function strokePolyline(points, style, width, dash = []) {
  if (points.length < 2) return;
  ctx.save();
  ctx.strokeStyle = style; ctx.lineWidth = width; ctx.lineCap = "round"; ctx.lineJoin = "round"; ctx.setLineDash(dash);
  ctx.beginPath();
  points.forEach(([x, y], i) => { const [cx, cy] = worldToCanvas(x, y); if (i) ctx.lineTo(cx, cy); else ctx.moveTo(cx, cy); });
  ctx.stroke();
  ctx.restore();
}

function drawPose(pose, colour, label) {
  if (!pose) return;
  const [cx, cy] = worldToCanvas(pose.x, pose.y);
  const len = 18;
  ctx.save();
  ctx.fillStyle = colour; ctx.strokeStyle = colour; ctx.lineWidth = 3;
  ctx.beginPath(); ctx.arc(cx, cy, 6, 0, 2 * Math.PI); ctx.fill();
  ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(cx + len * Math.cos(pose.yaw), cy - len * Math.sin(pose.yaw)); ctx.stroke();
  ctx.font = "bold 13px system-ui"; ctx.fillText(label, cx + 8, cy - 8);
  ctx.restore();
}

function drawPlan(plan) {
  const states = plan.states;
  const robot = plan.robot;
  const xy = states.map((s) => [s.x, s.y]);
  const fw = robot.footprint_width_m, fl = robot.footprint_length_m;
  const clearance = Math.max(0, Math.min(plan.min_clearance_m ?? 0, 1));
  // clearance band (footprint swept, widened by the minimum clearance) and the swept footprint
  strokePolyline(xy, "rgba(46,125,50,0.18)", (fw + 2 * clearance) * pxPerM());
  strokePolyline(xy, "rgba(21,101,192,0.25)", fw * pxPerM());
  // footprints every FOOTPRINT_SPACING_M, coloured by roll
  let last = -Infinity;
  states.forEach((s, i) => {
    if (s.s - last < FOOTPRINT_SPACING_M && i !== states.length - 1) return;
    last = s.s;
    const [cx, cy] = worldToCanvas(s.x, s.y);
    ctx.save();
    ctx.translate(cx, cy); ctx.rotate(-s.yaw);
    ctx.strokeStyle = rollColour(s.roll, robot.max_roll_rad); ctx.lineWidth = 1.5;
    if (robot.footprint) {  // the padded footprint polygon (robot frame, y left; the canvas y points down)
      ctx.beginPath();
      robot.footprint.forEach(([px, py], k) => {
        if (k === 0) ctx.moveTo(px * pxPerM(), -py * pxPerM()); else ctx.lineTo(px * pxPerM(), -py * pxPerM());
      });
      ctx.closePath(); ctx.stroke();
    } else {
      ctx.strokeRect((-fl / 2) * pxPerM(), (-fw / 2) * pxPerM(), fl * pxPerM(), fw * pxPerM());
    }
    ctx.restore();
  });
  // the path, each segment coloured by its roll
  for (let i = 1; i < states.length; i++) {
    strokePolyline([xy[i - 1], xy[i]], rollColour(states[i].roll, robot.max_roll_rad), 3);
  }
}

function draw() {
  if (!viewer.info || !viewer.image) return;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(viewer.image, 0, 0, canvas.width, canvas.height);
  if (viewer.plan) drawPlan(viewer.plan);
  if (viewer.sim) {
    strokePolyline(viewer.sim.trajectory.map((r) => [r.x, r.y]), "#000", 2);
    strokePolyline(viewer.sim.estimate.map((r) => [r.x, r.y]), "#d500f9", 1.5, [5, 4]);
  }
  if (viewer.rec) {
    strokePolyline(viewer.rec.samples.map((r) => [r.x, r.y]), "#ff6f00", 3, [8, 4]);
  }
  drawPose(viewer.start, "#2e7d32", "start");
  drawPose(viewer.goal, "#c62828", "goal");
}

// ------------------------------------------------------------------------------------ numbers

// the cells of each result panel: cleared on every new request and on failure, so no number outlives its answer
const PANELS = {
  plan: ["n-status", "n-length", "n-duration", "n-time", "n-expansions", "n-clearance", "n-roll", "n-why"],
  sim: ["s-status", "s-why", "s-rms", "s-max", "s-final", "s-est"],
  rec: ["r-status", "r-why", "r-mode", "r-length", "r-pos", "r-p"],
};
function clearPanel(kind) {
  viewer[kind] = null;
  for (const id of PANELS[kind]) { $(id).textContent = "–"; $(id).classList.remove("failed"); }
}
function showFailure(kind, why) {
  const cell = $(kind === "plan" ? "n-status" : `${kind[0]}-status`);
  cell.textContent = "failed"; cell.classList.add("failed");
  $(kind === "plan" ? "n-why" : `${kind[0]}-why`).textContent = why;
}

function showPlan(plan) {
  $("n-status").textContent = plan.status;
  $("n-length").textContent = fmt(plan.length_m, "m");
  $("n-duration").textContent = fmt(plan.duration_s, "s", 1);
  $("n-time").textContent = fmt(plan.planning_time_s * 1000, "ms", 0);
  $("n-expansions").textContent = String(plan.expansions);
  $("n-clearance").textContent = fmt(plan.min_clearance_m, "m");
  const maxRoll = Math.max(...plan.states.map((s) => Math.abs(s.roll)));
  $("n-roll").textContent = fmt((maxRoll * 180) / Math.PI, "°", 1);
}
const poseText = (p) => (p ? `${p.x.toFixed(2)}, ${p.y.toFixed(2)}, ${((p.yaw * 180) / Math.PI).toFixed(0)}°` : "–");

function refreshControls() {
  $("n-start").textContent = poseText(viewer.start);
  $("n-goal").textContent = poseText(viewer.goal);
  const ready = viewer.ready && !viewer.busy && viewer.start && viewer.goal;
  $("plan").disabled = !ready;
  $("reconfigure").disabled = !ready;
  $("live").disabled = !ready;
  $("simulate").disabled = !(ready && viewer.plan);
}

// ------------------------------------------------------------------------------------ map loading

async function loadMap(name) {
  viewer.ready = false; viewer.error = null; clearPanel("plan"); clearPanel("sim"); clearPanel("rec"); refreshControls();
  status(`loading ${name}…`);
  const info = await api("GET", `/v1/maps/${encodeURIComponent(name)}`);
  const image = new Image();
  await new Promise((resolve, reject) => {
    image.onload = resolve;
    image.onerror = () => reject(new Error(`cannot load the image of ${name}`));
    image.src = `/v1/maps/${encodeURIComponent(name)}.png`;
  });
  viewer.map = name; viewer.info = info; viewer.image = image;
  viewer.scale = Math.min(MAX_W / info.width, MAX_H / info.height);
  canvas.width = Math.round(info.width * viewer.scale);
  canvas.height = Math.round(info.height * viewer.scale);
  viewer.start = viewer.goal = null;
  viewer.ready = true;
  draw(); refreshControls();
  status(`${name}: ${info.size_m[0].toFixed(1)} m × ${info.size_m[1].toFixed(1)} m at ${info.resolution_m} m`);
}

// ------------------------------------------------------------------------------------ interaction

let dragging = null;
function eventWorld(ev) {
  const r = canvas.getBoundingClientRect();
  return canvasToWorld((ev.clientX - r.left) * (canvas.width / r.width), (ev.clientY - r.top) * (canvas.height / r.height));
}
canvas.addEventListener("mousedown", (ev) => {
  if (!viewer.ready) return;
  const [x, y] = eventWorld(ev);
  const which = $("mode").value;
  if (which === "obstacle") { reportObstacle(x, y); return; }
  viewer[which] = { x, y, yaw: viewer[which]?.yaw ?? 0 };
  dragging = which;
  draw(); refreshControls();
});
canvas.addEventListener("mousemove", (ev) => {
  if (!dragging) return;
  const [x, y] = eventWorld(ev);
  const p = viewer[dragging];
  if (Math.hypot(x - p.x, y - p.y) > 0.05) p.yaw = Math.atan2(y - p.y, x - p.x);
  draw(); refreshControls();
});
window.addEventListener("mouseup", () => {
  if (!dragging) return;
  if (dragging === "start") $("mode").value = "goal";
  dragging = null;
});

// run one request: its panel (and those that depend on it) is cleared first; a failure says "failed" and why
async function run(label, kind, fn) {
  viewer.busy = true; viewer.error = null;
  for (const k of { plan: ["plan", "sim", "rec"], sim: ["sim", "rec"], rec: ["plan", "sim", "rec"] }[kind]) clearPanel(k);
  refreshControls(); draw(); status(`${label}…`);
  try {
    const failure = await fn();
    if (failure) throw failure;
    status(`${label}: done`);
  } catch (err) {
    viewer.error = err.message;
    showFailure(kind, err.body?.error_msg || err.message);
    status(`${label} failed: ${err.message}`);
  } finally {
    viewer.busy = false; refreshControls(); draw();
  }
}

$("plan").addEventListener("click", () => run("plan", "plan", async () => {
  const body = { map: viewer.map, robot: $("robot").value, start: viewer.start, goal: viewer.goal };
  viewer.lastRequest = body;
  $("n-status").textContent = "planning";
  const plan = await api("POST", "/v1/plan", body);
  viewer.plan = plan;
  showPlan(plan);
}));

function showSim(sim) {
  const m = sim.metrics;
  $("s-status").textContent = sim.status;
  $("s-rms").textContent = fmt(m.cross_track_rms_m, "m", 3);
  $("s-max").textContent = fmt(m.cross_track_max_m, "m", 3);
  $("s-final").textContent = fmt(m.final_position_error_m, "m", 3);
  $("s-est").textContent = fmt(m.estimate_error_max_m, "m", 3);
}

$("simulate").addEventListener("click", () => run("simulate", "sim", async () => {
  const request = { map: viewer.map, path: viewer.plan, robot: viewer.plan.robot.name };
  try {
    viewer.sim = await api("POST", "/v1/simulate", request);
  } catch (err) {
    if (!err.body?.metrics) throw err;
    viewer.sim = err.body;  // the robot collided or missed the goal: draw what it did, and say it failed
    showSim(err.body);
    return err;
  }
  showSim(viewer.sim);
  return null;
}));

$("reconfigure").addEventListener("click", () => run("reconfigure", "rec", async () => {
  const rec = await api("POST", "/v1/reconfigure", {
    map: viewer.map, start: [viewer.start.x, viewer.start.y], goal: [viewer.goal.x, viewer.goal.y],
  });
  viewer.rec = rec;
  $("r-status").textContent = rec.status;
  $("r-mode").textContent = `${rec.method} / ${rec.mode}`;
  $("r-length").textContent = fmt(rec.length_m, "m");
  $("r-pos").textContent = fmt(rec.final.position_error_m * 1000, "mm", 2);
  $("r-p").textContent = fmt((rec.final.p_from_top_rad * 180) / Math.PI, "°", 3);
}));

// ------------------------------------------------------------------------------------ live session

async function reloadLiveMap() {
  const image = new Image();
  await new Promise((resolve, reject) => {
    image.onload = resolve;
    image.onerror = () => reject(new Error("cannot load the live map"));
    image.src = `/v1/sessions/${viewer.live.id}/map.png?t=${Date.now()}`;
  });
  viewer.image = image;
  draw();
}

function showLive(status) {
  $("l-replans").textContent = String(status.replans);
  const last = status.last_replan;
  $("l-last").textContent = last ? `${last.reason}, ${last.ok ? "ok" : "failed " + last.error_code}, ` +
    `${(last.latency_s * 1000).toFixed(0)} ms` : "–";
  $("l-known").textContent = `${(status.known_fraction * 100).toFixed(1)} %`;
}

$("live").addEventListener("click", () => run("live session", "plan", async () => {
  if (viewer.live) { viewer.live.events.close(); await api("DELETE", `/v1/sessions/${viewer.live.id}`).catch(() => null); }
  const body = { map: viewer.map, robot: $("robot").value, start: viewer.start, goal: viewer.goal };
  const session = await api("POST", "/v1/sessions", body);
  const events = new EventSource(`/v1/sessions/${session.id}/events`);
  viewer.live = { id: session.id, events };
  $("l-id").textContent = session.id;
  viewer.plan = session.path; viewer.sim = viewer.rec = null;
  if (session.path) showPlan(session.path);
  showLive(session.status);
  events.addEventListener("replan", (e) => {
    const data = JSON.parse(e.data);
    viewer.plan = data.path;
    if (data.path) showPlan(data.path); else $("n-status").textContent = `failed: ${data.replan.error_msg}`;
    showLive(data.status);
    reloadLiveMap().catch((err) => status(err.message));
  });
  events.addEventListener("map", () => reloadLiveMap().catch((err) => status(err.message)));
}));

// a 0.6 m obstacle reported as points seen from the start (as a range sensor on the robot would)
async function reportObstacle(x, y) {
  if (!viewer.live) { status("start a live session first"); return; }
  const points = [];
  for (let dx = -0.3; dx <= 0.3; dx += 0.05) for (let dy = -0.3; dy <= 0.3; dy += 0.05) points.push([x + dx, y + dy, 0.3]);
  const origin = [viewer.start.x, viewer.start.y, 0.3];
  try {
    await api("POST", `/v1/sessions/${viewer.live.id}/observations`, { points: { points, origin } });
    await reloadLiveMap();
  } catch (err) { status(`obstacle: ${err.message}`); }
}

$("map").addEventListener("change", () => loadMap($("map").value).catch((e) => status(e.message)));

async function init() {
  const [maps, robots] = await Promise.all([api("GET", "/v1/maps"), api("GET", "/v1/robots")]);
  for (const m of maps) $("map").add(new Option(`${m.name} (${m.kind})`, m.name));
  for (const r of robots) { viewer.robots[r.name] = r; $("robot").add(new Option(r.name, r.name)); }
  if (robots.some((r) => r.name === "zju-60")) $("robot").value = "zju-60";
  const wanted = new URLSearchParams(location.search).get("map");
  if (wanted && maps.some((m) => m.name === wanted)) $("map").value = wanted;
  if (maps.length) await loadMap($("map").value);
  else status("no maps in the maps folder");
}
init().catch((e) => status(`cannot start: ${e.message}`));
