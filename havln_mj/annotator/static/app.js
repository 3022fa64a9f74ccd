// The annotation page: a map of the scan, the agent's view, and people to place.
// State lives here; every change of the people is sent to the server, which checks it and
// answers what the simulator will make of it.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const ROOM_COLOURS = ["#fbb4ae", "#b3cde3", "#ccebc5", "#decbe4", "#fed9a6", "#ffffcc",
                      "#e5d8bd", "#fddaec", "#f2f2f2"];
const $ = (id) => document.getElementById(id);

const state = {
  plan: null, catalog: null, people: [], level: 0,
  vp: null,          // selected viewpoint id
  person: null,      // viewpoint of the selected person, or null
  heading: 0, elevation: 0, t: 0,
  version: 0, dirty: false,
};
let vpById = new Map();

// ---------------------------------------------------------------- server

async function api(method, url, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  const res = await fetch(url, init);
  const data = await res.json();
  if (!res.ok) throw new Error(data.error || res.statusText);
  return data;
}

function status(text, error = false) {
  const el = $("status");
  el.textContent = text;
  el.classList.toggle("error", error);
}

async function putPeople(people, message) {
  try {
    state.people = await api("PUT", "/api/people", people);
    state.version += 1;
    setDirty(true);
    status(message);
  } catch (err) {
    status(err.message, true);
  }
  drawPeople();
  showForm();
  showView();
}

function setDirty(dirty) {
  state.dirty = dirty;
  $("dirty").textContent = dirty ? "unsaved changes" : "";
}

// ---------------------------------------------------------------- map

function el(tag, attrs, parent) {
  const node = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (parent) parent.appendChild(node);
  return node;
}

function drawMap() {
  const svg = $("map");
  svg.replaceChildren();
  const plan = state.plan, level = state.level;
  const vps = plan.viewpoints.filter((v) => v.level === level);
  let [x0, y0, x1, y1] = plan.bounds;
  if (vps.length) {  // frame this level's viewpoints, with room around them
    x0 = Math.min(...vps.map((v) => v.x)) - 2; x1 = Math.max(...vps.map((v) => v.x)) + 2;
    y0 = Math.min(...vps.map((v) => v.y)) - 2; y1 = Math.max(...vps.map((v) => v.y)) + 2;
  }
  svg.setAttribute("viewBox", `${x0} ${-y1} ${x1 - x0} ${y1 - y0}`);
  const labels = [...new Set(plan.rooms.map((r) => r.label))].sort();
  const g = el("g", {}, svg);
  for (const room of plan.rooms.filter((r) => r.level === level)) {
    const pts = room.polygon.map(([x, y]) => `${x},${-y}`).join(" ");
    const fill = ROOM_COLOURS[labels.indexOf(room.label) % ROOM_COLOURS.length];
    el("polygon", { points: pts, class: "room", fill, "fill-opacity": 0.55 }, g);
    if (room.label !== "-") {
      const cx = room.polygon.reduce((s, p) => s + p[0], 0) / room.polygon.length;
      const cy = room.polygon.reduce((s, p) => s + p[1], 0) / room.polygon.length;
      el("text", { x: cx, y: -cy, class: "room-name" }, g).textContent = room.name;
    }
  }
  for (const f of plan.furniture.filter((f) => f.level === level)) {
    const [a, b, c, d] = f.box;
    el("rect", { x: a, y: -d, width: c - a, height: d - b, class: "furn" }, g);
  }
  for (const [a, b, c, d] of plan.walls[level] || []) {
    el("line", { x1: a, y1: -b, x2: c, y2: -d, class: "wall" }, g);
  }
  for (const [i, j] of plan.edges) {
    const a = plan.viewpoints[i], b = plan.viewpoints[j];
    if (a.level === level && b.level === level) {
      el("line", { x1: a.x, y1: -a.y, x2: b.x, y2: -b.y, class: "edge" }, g);
    }
  }
  for (const v of vps) {
    const c = el("circle", { cx: v.x, cy: -v.y, r: 0.13, "data-id": v.id,
                             class: v.included ? "vp" : "vp excluded" }, g);
    const title = el("title", {}, c);
    title.textContent = `${v.id}${v.region_name ? " (" + v.region_name + ")" : ""}` +
      (v.included ? "" : " — excluded from navigation");
    c.addEventListener("click", () => selectViewpoint(v.id));
  }
  el("g", { id: "selection" }, svg);
  el("g", { id: "peoplelayer" }, svg);
  drawSelection();
  drawPeople();
}

function drawSelection() {
  const g = $("selection");
  if (!g) return;
  g.replaceChildren();
  const v = vpById.get(state.vp);
  if (!v || v.level !== state.level) return;
  const h = state.heading * Math.PI / 180;
  el("circle", { cx: v.x, cy: -v.y, r: 0.3, class: "sel-ring" }, g);
  el("line", { x1: v.x, y1: -v.y, x2: v.x + 1.2 * Math.sin(h), y2: -(v.y + 1.2 * Math.cos(h)),
               class: "cam" }, g);
}

function drawPeople() {
  const g = $("peoplelayer");
  if (!g) return;
  g.replaceChildren();
  for (const p of state.people) {
    const v = vpById.get(p.viewpoint);
    if (!v || v.level !== state.level) continue;
    const h = p.heading_deg * Math.PI / 180;
    el("circle", { cx: v.x, cy: -v.y, r: 1.0, class: "radius" }, g);
    el("line", { x1: v.x, y1: -v.y, x2: v.x + 0.6 * Math.sin(h), y2: -(v.y + 0.6 * Math.cos(h)),
                 class: "facing" }, g);
    const dot = el("circle", { cx: v.x, cy: -v.y, r: 0.24, "data-vp": p.viewpoint,
                               class: p.viewpoint === state.person ? "person sel" : "person" }, g);
    el("title", {}, dot).textContent = `${said(p)} — ${p.viewpoint}`;
    dot.addEventListener("pointerdown", (ev) => startDrag(ev, p.viewpoint));
  }
  $("count").textContent = `(${state.people.length})`;
  const list = $("people");
  list.replaceChildren();
  for (const p of state.people) {
    const li = document.createElement("li");
    li.dataset.vp = p.viewpoint;
    li.className = p.viewpoint === state.person ? "sel" : "";
    li.innerHTML = "<span></span><small></small>";
    li.firstChild.textContent = said(p);
    li.lastChild.textContent = `${p.sentence.split(":")[0]} · motion ${p.model} · ` +
      `facing ${Math.round(p.heading_deg)}° · ${p.viewpoint}`;
    li.addEventListener("click", () => selectPerson(p.viewpoint));
    list.appendChild(li);
  }
}

// What a person does, as the placement file says it (its sentence without the region).
function said(p) {
  return p.sentence.slice(p.sentence.indexOf(":") + 1);
}

function svgPoint(ev) {
  const svg = $("map");
  const pt = svg.createSVGPoint();
  pt.x = ev.clientX; pt.y = ev.clientY;
  const p = pt.matrixTransform(svg.getScreenCTM().inverse());
  return [p.x, -p.y];
}

function nearestViewpoint([x, y], within) {
  let best = null, dist = within;
  for (const v of state.plan.viewpoints) {
    if (v.level !== state.level) continue;
    const d = Math.hypot(v.x - x, v.y - y);
    if (d < dist) { best = v; dist = d; }
  }
  return best;
}

function startDrag(ev, from) {
  ev.preventDefault();
  const dot = ev.target;
  let moved = false;
  const move = (e) => {
    const [x, y] = svgPoint(e);
    dot.setAttribute("cx", x); dot.setAttribute("cy", -y);
    moved = true;
  };
  const up = (e) => {
    window.removeEventListener("pointermove", move);
    window.removeEventListener("pointerup", up);
    const target = moved ? nearestViewpoint(svgPoint(e), 1.0) : null;
    if (target && target.id !== from) movePerson(from, target.id);
    else { drawPeople(); selectPerson(from); }
  };
  window.addEventListener("pointermove", move);
  window.addEventListener("pointerup", up);
}

// ---------------------------------------------------------------- selection and view

function showLevel(level) {
  if (level === state.level) return;
  state.level = level;
  $("level").value = level;
  drawMap();
}

function selectViewpoint(id) {
  const v = vpById.get(id);
  state.vp = id;
  showLevel(v.level);
  $("vpinfo").textContent = `Viewpoint ${id}` + (v.region_name ? ` · ${v.region_name}` : "") +
    (v.included ? "" : " · excluded from navigation");
  if (!state.person) {
    if (v.region && regionByCode(v.region)) setRegion(v.region);
    $("heading").value = Math.round(v.face_deg);
  }
  drawSelection();
  showForm();
  showView();
}

function selectPerson(vp) {
  const p = state.people.find((q) => q.viewpoint === vp);
  state.person = p ? vp : null;
  if (p) {
    setRegion(state.catalog.regions.find((r) => r.activities.some((a) => a.id === p.activity)).code);
    $("activity").value = p.activity;
    $("model").value = p.model;
    $("heading").value = Math.round(p.heading_deg);
    const v = vpById.get(vp);
    showLevel(v.level);
    // Stand on a neighbouring viewpoint, looking at them.
    const vps = state.plan.viewpoints;
    const near = state.plan.edges.filter(([i, j]) => vps[i].id === vp || vps[j].id === vp)
      .map(([i, j]) => (vps[i].id === vp ? vps[j] : vps[i]));
    if (near.length) {
      state.vp = near[0].id;
      state.heading = (Math.atan2(v.x - near[0].x, v.y - near[0].y) * 180 / Math.PI + 360) % 360;
      $("vpinfo").textContent = `Viewpoint ${state.vp} (looking at the person)`;
    }
    $("preview").src = `/api/preview.mp4?viewpoint=${encodeURIComponent(vp)}&v=${state.version}`;
  }
  drawPeople();
  drawSelection();
  showForm();
  showView();
}

function showView() {
  if (!state.vp) return;
  const q = new URLSearchParams({ viewpoint: state.vp, heading: state.heading,
                                  elevation: state.elevation, t: state.t, v: state.version });
  $("view").src = `/api/view.png?${q}`;
  $("pose").textContent = `heading ${Math.round(state.heading)}° · elevation ${state.elevation}°`;
}

function turn(dh, de) {
  state.heading = ((state.heading + dh) % 360 + 360) % 360;
  state.elevation = Math.max(-60, Math.min(60, state.elevation + de));
  drawSelection();
  showView();
}

// ---------------------------------------------------------------- the person form

function regionByCode(code) {
  return state.catalog.regions.find((r) => r.code === code);
}

function setRegion(code) {
  $("region").value = code;
  const acts = $("activity");
  acts.replaceChildren();
  for (const a of regionByCode(code).activities) {
    const o = document.createElement("option");
    o.value = a.id;
    o.textContent = a.text + (a.walks ? " (walks)" : "") +
      (a.sits ? " (sits: needs a seat, not in HA3D placements)" : "");
    o.disabled = a.sits;
    acts.appendChild(o);
  }
  const first = [...acts.options].find((o) => !o.disabled);
  if (first) acts.value = first.value;
}

function showForm() {
  const p = state.people.find((q) => q.viewpoint === state.person);
  const occupied = state.people.some((q) => q.viewpoint === state.vp);
  $("formtitle").textContent = p ? `Person on ${p.viewpoint}` : "New person";
  $("place").disabled = !!p || !state.vp || occupied;
  $("move").disabled = !p || !state.vp || occupied;
  $("delete").disabled = !p;
  $("deselect").disabled = !p;
  $("plays").textContent = p ? p.note : "";
  if (!p) $("preview").removeAttribute("src");
}

function formPerson(vp, sentence) {
  return { viewpoint: vp, activity: $("activity").value, model: Number($("model").value),
           heading_deg: Number($("heading").value) || 0, sentence };
}

function editPerson() {
  const p = state.people.find((q) => q.viewpoint === state.person);
  if (!p) return;
  const people = state.people.map((q) => (q === p ? formPerson(p.viewpoint, p.sentence) : q));
  putPeople(people, `changed the person on ${p.viewpoint}`).then(() => selectPerson(p.viewpoint));
}

function movePerson(from, to) {
  const people = state.people.map((q) => (q.viewpoint === from ? { ...q, viewpoint: to } : q));
  state.person = to;
  putPeople(people, `moved a person from ${from} to ${to}`).then(() => selectPerson(to));
}

// ---------------------------------------------------------------- start

function wire() {
  $("level").addEventListener("change", (e) => showLevel(Number(e.target.value)));
  $("region").addEventListener("change", (e) => { setRegion(e.target.value); editPerson(); });
  for (const id of ["activity", "model", "heading"]) $(id).addEventListener("change", editPerson);
  $("left").onclick = () => turn(-30, 0);
  $("right").onclick = () => turn(30, 0);
  $("up").onclick = () => turn(0, 15);
  $("down").onclick = () => turn(0, -15);
  $("time").addEventListener("input", (e) => {
    state.t = Number(e.target.value); $("tval").textContent = `${state.t} s`; showView();
  });
  $("place").onclick = () => {
    const vp = state.vp;
    state.person = vp;
    putPeople([...state.people, formPerson(vp, "")], `placed a person on ${vp}`)
      .then(() => selectPerson(vp));
  };
  $("move").onclick = () => movePerson(state.person, state.vp);
  $("delete").onclick = () => {
    const vp = state.person;
    state.person = null;
    putPeople(state.people.filter((q) => q.viewpoint !== vp), `deleted the person on ${vp}`);
  };
  $("deselect").onclick = () => { state.person = null; drawPeople(); showForm(); };
  $("save").onclick = async () => {
    try {
      const r = await api("POST", "/api/save", { path: $("path").value });
      $("path").value = r.path;
      setDirty(false);
      status(`saved ${r.people} people to ${r.path}`);
    } catch (err) { status(err.message, true); }
  };
  $("load").onclick = async () => {
    try {
      const r = await api("POST", "/api/load", { path: $("path").value });
      state.people = r.people; state.person = null; state.version += 1;
      $("path").value = r.path;
      setDirty(false);
      drawPeople(); showForm(); showView();
      status(`loaded ${r.people.length} people from ${r.path}`);
    } catch (err) { status(err.message, true); }
  };
  document.addEventListener("keydown", (e) => {
    if (["INPUT", "SELECT"].includes(document.activeElement.tagName)) return;
    const keys = { ArrowLeft: [-30, 0], ArrowRight: [30, 0], ArrowUp: [0, 15], ArrowDown: [0, -15] };
    if (keys[e.key]) { e.preventDefault(); turn(...keys[e.key]); }
  });
  window.addEventListener("beforeunload", (e) => { if (state.dirty) e.preventDefault(); });
}

async function start() {
  wire();
  try {
    const scene = await api("GET", "/api/scene");
    Object.assign(state, { plan: scene.plan, catalog: scene.catalog, people: scene.people });
    vpById = new Map(scene.plan.viewpoints.map((v) => [v.id, v]));
    $("scene").textContent = scene.plan.description;
    $("path").value = scene.placements;
    $("view").width = scene.view.width;
    for (const lv of scene.plan.levels) {
      $("level").add(new Option(`${lv.index} (floor ${lv.floor} m)`, lv.index));
    }
    for (const r of scene.catalog.regions) $("region").add(new Option(r.name, r.code));
    for (const m of scene.catalog.models) $("model").add(new Option(`motion ${m}`, m));
    setRegion(scene.catalog.regions[0].code);
    drawMap();
    const first = scene.plan.viewpoints.find((v) => v.included);
    if (first) selectViewpoint(first.id);
    status(`ready: ${scene.people.length} people loaded from ${scene.placements}`);
  } catch (err) {
    status(err.message, true);
  }
}

start();
