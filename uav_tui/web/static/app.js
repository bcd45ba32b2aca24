// uav-tui side page: WebRTC video, status over a websocket, target selection and F1-F4 over POST.
"use strict";

const token = new URLSearchParams(location.search).get("token") || "";
const auth = { "Content-Type": "application/json", "Authorization": "Bearer " + token };
const $ = (id) => document.getElementById(id);
const video = $("video"), stage = $("stage"), box = $("box");
const CLICK_PX = 8;  // a press that moves less than this is a click: select around the point

// -- commands --------------------------------------------------------------------------------------

async function post(path, body) {
  let ok = false, text;
  try {
    const response = await fetch(path, { method: "POST", headers: auth, body: JSON.stringify(body) });
    ok = response.ok;
    text = await response.text();
    try { text = JSON.parse(text).message; } catch (e) { /* plain-text error */ }
  } catch (e) {
    text = "no connection: " + e;
  }
  const reply = $("reply");
  reply.textContent = reply.title = text;
  reply.className = ok ? "reply" : "reply bad";
  return ok;
}

for (const button of document.querySelectorAll("nav button")) {
  button.addEventListener("click", () => post("/api/command", { command: button.dataset.command }));
}
document.addEventListener("keydown", (e) => {
  const n = ["F1", "F2", "F3", "F4"].indexOf(e.key);
  if (n >= 0) { e.preventDefault(); post("/api/command", { command: "f " + (n + 1) }); }
});

// -- target selection: drag a box or click, in normalized picture coordinates ----------------------

// Where the picture really is inside the <video> element (object-fit: contain letterboxes it).
function pictureRect() {
  const r = video.getBoundingClientRect(), vw = video.videoWidth, vh = video.videoHeight;
  if (!vw || !vh) return null;
  const scale = Math.min(r.width / vw, r.height / vh), w = vw * scale, h = vh * scale;
  return { left: r.left + (r.width - w) / 2, top: r.top + (r.height - h) / 2, width: w, height: h };
}

const clamp01 = (v) => Math.min(1, Math.max(0, v));
let drag = null;

function showBox(x0, y0, x1, y1) {
  const s = stage.getBoundingClientRect();
  Object.assign(box.style, {
    left: Math.min(x0, x1) - s.left + "px", top: Math.min(y0, y1) - s.top + "px",
    width: Math.abs(x1 - x0) + "px", height: Math.abs(y1 - y0) + "px",
  });
  box.hidden = false;
}

stage.addEventListener("pointerdown", (e) => {
  const pic = pictureRect();
  if (!pic || e.clientX < pic.left || e.clientX > pic.left + pic.width ||
      e.clientY < pic.top || e.clientY > pic.top + pic.height) return;  // outside the picture: letterbox
  stage.setPointerCapture(e.pointerId);
  drag = { id: e.pointerId, pic, x0: e.clientX, y0: e.clientY };
  e.preventDefault();
});

stage.addEventListener("pointermove", (e) => {
  if (!drag || e.pointerId !== drag.id) return;
  const { pic } = drag;
  const x = Math.min(Math.max(e.clientX, pic.left), pic.left + pic.width);
  const y = Math.min(Math.max(e.clientY, pic.top), pic.top + pic.height);
  showBox(drag.x0, drag.y0, x, y);
});

function endDrag(e, cancelled) {
  if (!drag || e.pointerId !== drag.id) return;
  const { pic, x0, y0 } = drag;
  drag = null;
  setTimeout(() => { box.hidden = true; }, 600);
  if (cancelled) return;
  const nx = (x) => clamp01((x - pic.left) / pic.width), ny = (y) => clamp01((y - pic.top) / pic.height);
  if (Math.hypot(e.clientX - x0, e.clientY - y0) < CLICK_PX) {
    post("/api/roi", { point: [nx(x0), ny(y0)] });
  } else {
    post("/api/roi", { rect: [nx(x0), ny(y0), nx(e.clientX), ny(e.clientY)] });
  }
}
stage.addEventListener("pointerup", (e) => endDrag(e, false));
stage.addEventListener("pointercancel", (e) => endDrag(e, true));

// The processor's box (frame pixels of a frame[0] x frame[1] camera) outlined over the picture.
function showTracked(tracked, frame) {
  const pic = pictureRect(), outline = $("tracked");
  if (!tracked || !pic || !frame[0] || !frame[1]) { outline.hidden = true; return; }
  const s = stage.getBoundingClientRect(), sx = pic.width / frame[0], sy = pic.height / frame[1];
  Object.assign(outline.style, {
    left: pic.left - s.left + tracked[0] * sx + "px", top: pic.top - s.top + tracked[1] * sy + "px",
    width: tracked[2] * sx + "px", height: tracked[3] * sy + "px",
  });
  outline.hidden = false;
}

// -- video -----------------------------------------------------------------------------------------

function setLink(text, bad) {
  $("link").textContent = $("link").title = "video: " + text;
  $("link").className = bad ? "badge bad" : "badge";
}

async function startVideo() {
  const pc = new RTCPeerConnection({ iceServers: [] });
  pc.addTransceiver("video", { direction: "recvonly" });
  window.addEventListener("pagehide", () => pc.close());  // tells the server at once that we left
  pc.ontrack = (e) => { video.srcObject = e.streams[0] || new MediaStream([e.track]); };
  pc.onconnectionstatechange = () => {
    setLink(pc.connectionState, pc.connectionState === "failed");
    if (pc.connectionState === "failed" || pc.connectionState === "disconnected") {
      pc.close();
      setTimeout(startVideo, 2000);
    }
  };
  await pc.setLocalDescription(await pc.createOffer());
  await new Promise((resolve) => {  // the server does not trickle: send every candidate at once
    if (pc.iceGatheringState === "complete") return resolve();
    pc.addEventListener("icegatheringstatechange", () => { if (pc.iceGatheringState === "complete") resolve(); });
    setTimeout(resolve, 3000);
  });
  const response = await fetch("/offer", {
    method: "POST", headers: auth,
    body: JSON.stringify({ sdp: pc.localDescription.sdp, type: pc.localDescription.type }),
  });
  if (!response.ok) {
    setLink(response.status + " " + (await response.text()), true);
    pc.close();
    setTimeout(startVideo, 5000);
    return;
  }
  await pc.setRemoteDescription(await response.json());
}

// -- status and events -----------------------------------------------------------------------------

const fmt = (v, digits, unit) => (v === null || v === undefined ? "-" : v.toFixed(digits) + unit);

function showStatus(message) {
  const s = message.status, p = s.pipeline || {}, t = s.telemetry || {};
  const auto = $("autonomy");
  auto.textContent = s.autonomy ? "AUTO ON" : "AUTO OFF";
  auto.className = s.autonomy ? "badge on" : "badge off";
  auto.title = s.autonomy_stop_reason || "";
  const stalled = s.source && s.source.stalled_since ? " camera STALLED" : "";
  let line = `${message.frame[0]}x${message.frame[1]}${stalled} cam ${fmt(p.capture_fps, 1, "")} ` +
    `proc ${fmt(p.processed_fps, 1, "")} fps age ${fmt(p.frame_age_ms, 0, "ms")} err ${p.errors ?? "-"}`;
  if (s.fc !== "none") {
    line += ` | hb ${fmt(s.heartbeat_age_s, 1, "s")} ${s.link_lost ? "LINK LOST, stale: " : ""}` +
      `${t.flight_mode || "?"} ${t.armed ? "ARMED" : "disarmed"}` +
      `${t.in_air ? " air" : ""} alt ${fmt(t.rel_alt_m, 1, "m")} bat ${fmt(t.battery_pct, 0, "%")}`;
    if (s.vehicle_problem) line += ` (${s.vehicle_problem})`;
  }
  if (s.box) line += ` | box ${s.box[0]},${s.box[1]} ${s.box[2]}x${s.box[3]}`;
  showTracked(s.box, message.frame);
  showTarget(s.target);
  showDetections(s.detections || [], s.detections_total || 0, s.tracks_total || 0);
  if (s.lock) line += ` | lock: ${s.lock}`;
  if (s.last_decision) line += ` | ${s.last_decision}`;
  if (s.gimbal) line += ` | ${s.gimbal}`;
  const host = s.processor_state;
  if (host) {
    line += host.isolation === "thread" ? " | processor in a platform thread" :
      ` | processor ${host.state}${host.pid ? " pid " + host.pid : ""}` +
      `${host.memory_mb === null ? "" : " " + host.memory_mb.toFixed(0) + " MB"}`;
  }
  if (s.processor_error) line += ` | processor error: ${s.processor_error}`;
  line += ` | ${message.viewers} watching`;
  $("status").textContent = line;
}

// Where the tracked box is on the ground, over the picture's corner (showing it moves nothing): the TUI's line
// (latitude,longitude, distance and bearing from the vehicle, 1-sigma uncertainty) or why it is not located.
function showTarget(target) {
  const line = $("target"), text = target && target.description;
  line.hidden = !text;
  line.textContent = text ? "target " + text : "";
  line.className = target && target.status !== "ok" ? "target warn" : "target";
}

// The processor's detections, over the picture's top corner: the few most confident (the status carries at most
// five), each with where it is on the ground, and how many more there are.
function showDetections(shown, total, tracks) {
  const list = $("detections");
  list.hidden = !total;
  list.title = tracks ? `${total} detected, ${tracks} tracks` : `${total} detected`;
  list.replaceChildren(...shown.map((d) => {
    const item = document.createElement("li"), t = d.target;
    const where = t.status === "ok" ?
      `${t.lat_deg.toFixed(6)},${t.lon_deg.toFixed(6)} ${t.distance_m.toFixed(0)} m at ` +
      `${String(Math.round(t.bearing_deg) % 360).padStart(3, "0")} deg +-${t.uncertainty_m.toFixed(1)} m` :
      `not located${t.status ? ": " + t.status : ""}`;
    const id = d.track_id === null || d.track_id === undefined ? "" : `#${d.track_id} `;
    item.textContent = `${id}${d.label} ${d.score.toFixed(2)} ${where}`;
    return item;
  }));
  if (total > shown.length) {
    const more = document.createElement("li");
    more.textContent = `+${total - shown.length} more`;
    list.append(more);
  }
}

function showEvent(e) {
  const item = document.createElement("li");
  item.className = e.level;
  const time = new Date(e.t_wall_ns / 1e6).toLocaleTimeString();
  item.textContent = `${time} ${e.level} ${e.kind} (${e.origin}): ${e.message}`;
  const list = $("events");
  list.prepend(item);
  while (list.children.length > 30) list.lastChild.remove();
}

function connectStatus() {
  const scheme = location.protocol === "https:" ? "wss:" : "ws:";
  const ws = new WebSocket(`${scheme}//${location.host}/ws?token=${encodeURIComponent(token)}`);
  ws.onmessage = (m) => {
    const message = JSON.parse(m.data);
    if (message.type === "status") showStatus(message);
    else if (message.type === "event") showEvent(message);
  };
  ws.onclose = () => { $("status").textContent = "status: disconnected, retrying..."; setTimeout(connectStatus, 2000); };
}

connectStatus();
startVideo().catch((e) => setLink(String(e), true));
