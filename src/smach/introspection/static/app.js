// The smach viewer page. Plain JavaScript, no libraries, nothing fetched from
// anywhere but the viewer's own server. The server lays the graph out and sends it
// as SVG (/api/svg); this script highlights states by toggling classes, pans and
// zooms, and shows the view the server folded from the records (/api/view, or the
// /api/stream server-sent events of a live run).
"use strict";

const S = {
  info: null,
  view: null,
  total: 0,
  first: 0,
  cursor: null, // null: follow the newest view (live); else the record count shown
  structureVersion: -1,
  collapsed: new Set(),
  autoCollapsed: false,
  focus: true, // collapse what is off the active path (until the user opens or closes a box)
  focusKey: null,
  selected: null,
  root: null,
  nodes: new Map(),
  edges: new Map(),
  touched: [],
  subs: new Map(),
  lastUserdata: new Map(),
  vb: null,
  full: null,
  fitted: false,
  playing: null,
  loadingSvg: null,
  timelineRange: null,
};
window.smachViewer = S;

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";

// A toolbar button, left of "Fit", that shows or hides a pane (gantt.js, scene.js);
// hidden until the pane has something to show.
window.smachPaneButton = (id, text, title, onClick) => {
  const button = document.createElement("button");
  button.id = id;
  button.textContent = text;
  button.title = title;
  button.hidden = true;
  button.onclick = onClick;
  $("fit").before(button);
  return button;
};

// What the control panel (control.js) and the orders panel (orders.js) both read: the
// server's /api/info (null when it cannot be read) and the per-run control token of
// the URL's #token=... (null without one).
window.smachServer = {
  info: () =>
    fetch("/api/info", { cache: "no-store" })
      .then((r) => r.json())
      .catch(() => null),
  token: () => {
    const m = /(?:^|[#&])token=([A-Za-z0-9_\-]+)/.exec(location.hash || "");
    return m ? m[1] : null;
  },
};

async function getJSON(url) {
  const r = await fetch(url, { cache: "no-store" });
  if (!r.ok) throw new Error(`${url}: ${r.status}`);
  return r.json();
}

function esc(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
}

function short(value, max = 160) {
  let text = typeof value === "string" ? JSON.stringify(value) : JSON.stringify(value, null, 0);
  if (text === undefined) text = String(value);
  return text.length > max ? text.slice(0, max) + "…" : text;
}

function rel(t) {
  const t0 = S.view && S.view.t0;
  if (typeof t !== "number" || typeof t0 !== "number") return "";
  return (t - t0).toFixed(3);
}

// -- graph -----------------------------------------------------------------------------
async function loadStructure(version) {
  const params = new URLSearchParams({ version: String(version) });
  for (const c of S.collapsed) params.append("c", c);
  if (S.focus) {
    params.append("focus", "1");
    for (const p of S.view ? S.view.active : []) params.append("a", p);
  }
  const text = await (await fetch(`/api/svg?${params}`, { cache: "no-store" })).text();
  const graph = $("graph");
  graph.innerHTML = text;
  const svg = graph.querySelector("svg");
  // A new structure (an executive compiled its plan) is fitted anew; a collapse or
  // expand of the same structure keeps the user's pan and zoom.
  if (version !== S.structureVersion) S.fitted = false;
  S.structureVersion = version;
  S.nodes = new Map();
  S.edges = new Map();
  S.touched = [];
  S.subs = new Map();
  for (const el of svg.querySelectorAll("[data-path]")) {
    if (!el.classList.contains("badge")) S.nodes.set(el.dataset.path, el);
  }
  for (const el of svg.querySelectorAll(".edge")) {
    S.edges.set(`${el.dataset.container}|${el.dataset.source}|${el.dataset.outcome}`, el);
  }
  if (S.focus && S.view) S.focusKey = focusKey(S.view);
  const rootCluster = svg.querySelector(".cluster");
  S.root = rootCluster ? rootCluster.dataset.path : null;
  if (!S.selected || !S.nodes.has(S.selected)) S.selected = S.root;
  const w = parseFloat(svg.getAttribute("width")) || 100;
  const h = parseFloat(svg.getAttribute("height")) || 100;
  S.full = { x: 0, y: 0, w, h };
  svg.setAttribute("width", "100%");
  svg.setAttribute("height", "100%");
  svg.setAttribute("preserveAspectRatio", "xMidYMid meet");
  if (!S.fitted || !S.vb) {
    fit();
    S.fitted = true;
  } else {
    setViewBox(S.vb);
  }
  if (!S.autoCollapsed && !S.focus) {
    S.autoCollapsed = true;
    if (autoCollapse(svg)) return loadStructure(version);
  }
}

// Big trees start with their deeper containers collapsed (click to open them).
function autoCollapse(svg) {
  const states = svg.querySelectorAll(".node.state").length;
  if (states <= 150) return false;
  for (const el of svg.querySelectorAll(".cluster.d2, .cluster.d3")) S.collapsed.add(el.dataset.path);
  return S.collapsed.size > 0;
}

// The boxes the focus view depends on: active paths that are containers (drawn as
// clusters or collapsed boxes) or not drawn at all (inside a collapsed box).
function focusKey(view) {
  return view.active.filter((p) => {
    const el = S.nodes.get(p);
    return !el || !el.classList.contains("state");
  }).join("|");
}

// A run entered or left a container: lay the graph out again around the active path.
function refocus(view) {
  if (!S.focus || S.loadingSvg) return false;
  if (focusKey(view) === S.focusKey) return false;
  S.fitted = false;
  S.loadingSvg = loadStructure(S.structureVersion).then(() => {
    S.loadingSvg = null;
    applyView(S.view, true);
  });
  return true;
}

function setFocus(on) {
  S.focus = on;
  $("focus").classList.toggle("on", on);
  if (on) {
    S.collapsed.clear();
    S.focusKey = null;
    if (S.view) refocus(S.view);
  }
}

function setViewBox(vb) {
  S.vb = vb;
  const svg = $("graph").querySelector("svg");
  if (svg) svg.setAttribute("viewBox", `${vb.x} ${vb.y} ${vb.w} ${vb.h}`);
}

function fit() {
  if (!S.full) return;
  const pad = 10;
  setViewBox({ x: -pad, y: -pad, w: S.full.w + 2 * pad, h: S.full.h + 2 * pad });
}

function clientToSvg(svg, x, y) {
  const pt = svg.createSVGPoint();
  pt.x = x;
  pt.y = y;
  return pt.matrixTransform(svg.getScreenCTM().inverse());
}

function installPanZoom() {
  const graph = $("graph");
  graph.addEventListener("wheel", (ev) => {
    const svg = graph.querySelector("svg");
    if (!svg || !S.vb) return;
    ev.preventDefault();
    const k = Math.exp(ev.deltaY * 0.0015);
    const p = clientToSvg(svg, ev.clientX, ev.clientY);
    const vb = S.vb;
    const w = Math.min(Math.max(vb.w * k, 60), S.full.w * 6 + 200);
    const h = (vb.h * w) / vb.w;
    setViewBox({ x: p.x - ((p.x - vb.x) * w) / vb.w, y: p.y - ((p.y - vb.y) * h) / vb.h, w, h });
  }, { passive: false });
  let drag = null;
  graph.addEventListener("pointerdown", (ev) => {
    if (ev.button !== 0) return;
    drag = { x: ev.clientX, y: ev.clientY, vb: { ...S.vb }, moved: false };
  });
  window.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    const svg = graph.querySelector("svg");
    const dx = ev.clientX - drag.x;
    const dy = ev.clientY - drag.y;
    if (!drag.moved && Math.abs(dx) + Math.abs(dy) < 4) return;
    drag.moved = true;
    graph.classList.add("dragging");
    const scale = drag.vb.w / svg.clientWidth;
    const scaleY = drag.vb.h / svg.clientHeight;
    const s = Math.max(scale, scaleY);
    setViewBox({ ...drag.vb, x: drag.vb.x - dx * s, y: drag.vb.y - dy * s });
  });
  window.addEventListener("pointerup", () => {
    graph.classList.remove("dragging");
    if (drag && drag.moved) S.justDragged = true;
    drag = null;
  });
  graph.addEventListener("click", (ev) => {
    if (S.justDragged) {
      S.justDragged = false;
      return;
    }
    const toggle = ev.target.closest("[data-toggle]");
    if (toggle) {
      const path = toggle.dataset.toggle;
      if (S.focus) {
        // Leaving the focus view: keep what it showed, then apply the user's click.
        for (const el of $("graph").querySelectorAll(".node.collapsed")) S.collapsed.add(el.dataset.path);
        setFocus(false);
      }
      if (S.collapsed.has(path)) S.collapsed.delete(path);
      else S.collapsed.add(path);
      select(path);
      refreshStructure();
      return;
    }
    const el = ev.target.closest("[data-path]");
    if (el && !el.classList.contains("outcome")) select(el.dataset.path);
  });
}

async function refreshStructure() {
  await loadStructure(S.structureVersion);
  if (S.view) applyView(S.view, true);
}

function select(path) {
  S.selected = path;
  if (S.view) renderSide(S.view);
  for (const el of $("graph").querySelectorAll(".selected")) el.classList.remove("selected");
  const el = S.nodes.get(path);
  if (el) el.classList.add("selected");
}

function nearestShown(path) {
  let p = path;
  while (p) {
    if (S.nodes.has(p)) return p;
    const i = p.lastIndexOf("/");
    if (i <= 0) return null;
    p = p.slice(0, i);
  }
  return null;
}

function mark(el, cls) {
  el.classList.add(cls);
  S.touched.push([el, cls]);
}

function applyGraph(view) {
  for (const [el, cls] of S.touched) el.classList.remove(cls);
  S.touched = [];
  const svg = $("graph").querySelector("svg");
  if (!svg) return;
  for (const b of svg.querySelectorAll(".badge")) b.remove();
  for (const [path, outcome] of Object.entries(view.outcomes)) {
    const el = S.nodes.get(path);
    if (el && el.classList.contains("state")) mark(el, "visited");
  }
  for (const path of view.active) {
    const shown = nearestShown(path);
    if (!shown) continue;
    mark(S.nodes.get(shown), shown === path ? "active" : "contains-active");
  }
  for (const [container, edge] of Object.entries(view.last_edges)) {
    const el = S.edges.get(`${container}|${edge[0]}|${edge[1]}`);
    if (el) {
      mark(el, "taken");
      el.querySelector("path").setAttribute("marker-end", "url(#arrow-taken)");
    }
  }
  for (const el of svg.querySelectorAll(".edge:not(.taken) path[marker-end='url(#arrow-taken)']")) {
    el.setAttribute("marker-end", "url(#arrow)");
  }
  let anyPreempt = false;
  for (const [path, state] of Object.entries(view.preempt)) {
    if (state !== "requested") continue;
    anyPreempt = true;
    const shown = nearestShown(path);
    if (!shown) continue;
    const el = S.nodes.get(shown);
    mark(el, "preempt");
    addBadge(svg, el);
  }
  $("preempt-flag").hidden = !anyPreempt;
  for (const path of Object.keys(view.error_paths)) {
    const shown = nearestShown(path);
    if (shown) mark(S.nodes.get(shown), "error");
  }
  if (S.root && view.root_outcome && !view.running) {
    const pill = S.nodes.get(`${S.root}:${view.root_outcome}`);
    if (pill) mark(pill, "reached");
  }
  // Second line of each state: running, or its last outcome and how often it ran.
  const activeSet = new Set(view.active);
  for (const [path, el] of S.nodes) {
    if (!el.classList.contains("state")) continue;
    let text = "";
    if (activeSet.has(path)) text = "running…";
    else if (view.outcomes[path] !== undefined) text = `→ ${view.outcomes[path]}`;
    const n = view.entered[path] || 0;
    if (n > 1) text += `  ×${n}`;
    if (S.subs.get(path) !== text) {
      S.subs.set(path, text);
      const sub = el.querySelector(".sub");
      if (sub) sub.textContent = text;
    }
  }
  const sel = S.nodes.get(S.selected);
  if (sel) sel.classList.add("selected");
  if ($("follow").checked && (S.cursor === null || S.playing)) keepInView(view);
}

function addBadge(svg, el) {
  const rect = el.querySelector("rect");
  const x = parseFloat(rect.getAttribute("x"));
  const y = parseFloat(rect.getAttribute("y"));
  const w = parseFloat(rect.getAttribute("width"));
  const g = document.createElementNS(SVGNS, "g");
  g.setAttribute("class", "badge");
  const bw = 112;
  const bx = el.classList.contains("cluster") ? x + w - bw - 8 : x + w / 2 - bw / 2;
  g.innerHTML = `<rect x="${bx}" y="${y - 9}" width="${bw}" height="15" rx="7"></rect>` +
    `<text x="${bx + bw / 2}" y="${y - 1.5}" text-anchor="middle">PREEMPT REQUESTED</text>`;
  svg.appendChild(g);
}

// Pan (not zoom) so that the active leaf states are in view.
function keepInView(view) {
  if (!S.vb) return;
  const leaves = view.active.map(nearestShown).filter((p) => p && S.nodes.get(p).classList.contains("node"));
  if (!leaves.length) return;
  let minX = Infinity, minY = Infinity, maxX = -Infinity, maxY = -Infinity;
  for (const p of leaves) {
    const r = S.nodes.get(p).querySelector("rect");
    const x = parseFloat(r.getAttribute("x")), y = parseFloat(r.getAttribute("y"));
    minX = Math.min(minX, x); minY = Math.min(minY, y);
    maxX = Math.max(maxX, x + parseFloat(r.getAttribute("width")));
    maxY = Math.max(maxY, y + parseFloat(r.getAttribute("height")));
  }
  const vb = S.vb;
  if (minX >= vb.x && maxX <= vb.x + vb.w && minY >= vb.y && maxY <= vb.y + vb.h) return;
  setViewBox({ ...vb, x: (minX + maxX) / 2 - vb.w / 2, y: (minY + maxY) / 2 - vb.h / 2 });
}

// -- side panels -------------------------------------------------------------------------
function containerOf(path) {
  const el = S.nodes.get(path);
  if (el && el.classList.contains("cluster")) return path;
  if (el && el.classList.contains("collapsed")) return path;
  const i = path.lastIndexOf("/");
  return i > 0 ? path.slice(0, i) : path;
}

function renderSide(view) {
  const path = S.selected || S.root;
  if (!path) return;
  $("sel-path").textContent = path;
  const el = S.nodes.get(path);
  const title = el ? (el.querySelector("title") || {}).textContent || "" : "";
  const type = (title.match(/\(([^)]*)\)$/) || [])[1] || "";
  const rows = [
    ["type", type],
    ["status", view.active.includes(path) ? "active" : view.outcomes[path] !== undefined ? "ran" : "not run"],
    ["last outcome", view.outcomes[path] ?? "–"],
    ["times entered", String(view.entered[path] || 0)],
  ];
  if (view.preempt[path]) rows.push(["preempt", view.preempt[path]]);
  if (view.error_paths[path]) rows.push(["error", view.error_paths[path]]);
  $("sel-info").innerHTML = "<dl>" + rows.map(([k, v]) => `<dt>${esc(k)}</dt><dd>${esc(v)}</dd>`).join("") + "</dl>";

  const container = containerOf(path);
  $("ud-path").textContent = container;
  const data = view.userdata[container] || {};
  const writers = view.writers[container] || {};
  const body = $("ud-table").tBodies[0];
  const keys = Object.keys(data).sort();
  const previous = S.lastUserdata.get(container) || {};
  const now = {};
  body.innerHTML = "";
  for (const key of keys) {
    const text = short(data[key], 2000);
    now[key] = text;
    const tr = document.createElement("tr");
    tr.dataset.key = key;
    if (previous[key] !== undefined && previous[key] !== text) tr.className = "changed";
    tr.innerHTML = `<td class="key">${esc(key)}</td><td class="value">${esc(text)}</td>` +
      `<td class="writer">${writers[key] ? "by " + esc(writers[key]) : ""}</td>`;
    body.appendChild(tr);
  }
  S.lastUserdata.set(container, now);
  $("ud-empty").hidden = keys.length > 0;
  renderPlan(view);
}

function renderPlan(view) {
  const section = $("plan");
  if (!view.plans.length && !view.decisions.length) {
    section.hidden = true;
    return;
  }
  section.hidden = false;
  const replans = view.decisions.filter((d) => d.decision === "replan").length;
  const repairs = view.decisions.filter((d) => d.decision === "repair").length;
  const running = view.running_step ? view.running_step.split("/").pop() : "";
  let html = `<div class="plan-summary">${view.plans.length} plan(s) · ${replans} replan(s) · ` +
    `${repairs} repair(s) · ${view.steps.length} step(s) run` +
    (running ? ` · now <b>${esc(running)}</b>` : "") + "</div>";
  const solved = view.plans;
  const shown = solved.slice(-2);
  html += `<div class="plans ${shown.length < 2 ? "single" : ""}" id="plan-columns">`;
  shown.forEach((plan, i) => {
    const label = shown.length === 2 ? (i === 0 ? "previous" : "current") : "current";
    const current = i === shown.length - 1;
    html += `<div class="plancol" data-plan="${plan.number}"><h3>${label}: plan #${plan.number}` +
      ` <span style="font-weight:400;color:#6b778c">(${esc(plan.status)}, ${plan.steps.length} steps)</span></h3>` +
      `<div class="why">${esc(plan.reason)}${plan.explanation ? " — " + esc(plan.explanation) : ""}</div><ol>`;
    plan.steps.forEach((step, k) => {
      let status = plan.status_of_steps[k] || "pending";
      if (current && status === "pending" && view.running && running && labelMatches(running, step)) status = "running";
      html += `<li class="s-${esc(status)}" title="${esc(status)}">${esc(step)}</li>`;
    });
    html += "</ol></div>";
  });
  html += "</div>";
  const decisions = view.decisions.slice(-8).reverse();
  if (decisions.length) {
    html += '<div class="decisions">';
    for (const d of decisions) {
      html += `<div class="decision"><b>${esc(d.decision)}</b>${esc(d.reason)}` +
        `<span style="color:#8391a7"> · t=${rel(d.time)} s</span></div>`;
    }
    html += "</div>";
  }
  $("plan-body").innerHTML = html;
}

// "03_PICK_CUP_TABLE" is the label plan_bridge gives "pick(cup, table)".
function labelMatches(label, step) {
  const words = step.replace(/[()]/g, " ").split(/[\s,]+/).filter(Boolean);
  const text = words.map((w) => w.replace(/[^A-Za-z0-9]+/g, "-").replace(/^-|-$/g, "").toUpperCase()).join("_");
  return label.replace(/^\d+_/, "") === text;
}

// -- timeline ---------------------------------------------------------------------------------
const QUIET = new Set(["state_entered", "state_exited", "userdata", "structure"]);

function describe(r) {
  switch (r.kind) {
    case "transition": return `${r.source} —${r.outcome}→ ${r.target}`;
    case "container_started": return `started ${r.container_type || ""} in ${(r.initial_states || []).join(", ")}`;
    case "container_terminated": return `finished with outcome ${r.outcome}`;
    case "state_entered": return "entered";
    case "state_exited": return `exited → ${r.outcome}`;
    case "preempt_requested": return "preempt requested";
    case "preempt_serviced": return "preempt serviced";
    case "error": return `${r.error_type}: ${r.message}`;
    case "userdata_written": return `${r.key} = ${short(r.value, 120)}${r.writer ? "  (by " + r.writer + ")" : ""}`;
    case "userdata": return `userdata snapshot: ${Object.keys(r.values || {}).join(", ")}`;
    case "structure": return "structure changed";
    case "resync": return `resynchronised: ${r.reason || ""}`;
    case "plan_computed": return `${r.reason}: ${r.status}, ${(r.steps || []).length} steps (${r.planner}, ${Number(r.planning_time_s || 0).toFixed(2)} s)`;
    case "executive_decision": return `${r.decision}: ${r.reason}`;
    case "step_finished": return `step ${r.index} ${r.action} → ${r.outcome}`;
    case "action_started": return `step ${r.index} ${r.action} started (planned at ${r.planned_start} for ${r.planned_duration} plan s)`;
    case "action_ended": return `step ${r.index} ${r.action} ended: ${r.outcome}`;
    case "observations_applied": return `observed ${(r.changed || []).join(", ")}`;
    case "scene": return `picture of the world${r.title ? ": " + r.title : ""}`;
    case "order": return `order ${r.order} ${r.status}${(r.robots || []).length ? " (" + r.robots.join(", ") + ")" : ""}` +
      `${r.status === "queued" && r.goal ? ": " + r.goal : ""}${r.reason ? ": " + r.reason : ""}`;
    case "control": return `${r.action} (from ${r.source})${r.details && r.details.reason ? ": " + r.details.reason : ""} → ${r.state}`;
    default: return short(r, 200);
  }
}

function shortPath(path) {
  if (!path) return "";
  const parts = path.split("/");
  return parts.length > 3 ? "…/" + parts.slice(-2).join("/") : path;
}

function timelineRow(r) {
  const tr = document.createElement("tr");
  tr.dataset.n = String(r.n);
  tr.dataset.kind = r.kind;
  if (r.kind === "error") tr.className = "err";
  tr.innerHTML = `<td class="n">${r.n + 1}</td><td class="t">${rel(r.time)}</td>` +
    `<td class="kind"><span class="k ${esc(r.kind)}">${esc(r.kind.replace(/_/g, " "))}</span></td>` +
    `<td class="where" title="${esc(r.path || "")}">${esc(shortPath(r.path || ""))}</td>` +
    `<td class="what">${esc(describe(r))}</td>`;
  return tr;
}

function visibleRecord(r) {
  return $("all-events").checked || !QUIET.has(r.kind);
}

function appendTimeline(records) {
  const box = $("timeline");
  const atBottom = box.scrollTop + box.clientHeight >= box.scrollHeight - 30;
  const body = $("events").tBodies[0];
  for (const r of records) if (visibleRecord(r)) body.appendChild(timelineRow(r));
  while (body.rows.length > 1500) body.deleteRow(0);
  if (atBottom) box.scrollTop = box.scrollHeight;
}

async function loadTimeline(end) {
  const records = await getJSON(`/api/records?start=${Math.max(0, end - 400)}&end=${end}`);
  const body = $("events").tBodies[0];
  body.innerHTML = "";
  appendTimeline(records);
  const box = $("timeline");
  box.scrollTop = box.scrollHeight;
  const last = body.rows[body.rows.length - 1];
  if (last && S.cursor !== null) last.classList.add("current");
}

// -- cursor -----------------------------------------------------------------------------------
function updateCursor(view) {
  const slider = $("slider");
  slider.min = String(S.first);
  slider.max = String(S.total);
  const at = S.cursor === null ? S.total : S.cursor;
  slider.value = String(at);
  const t = view && view.time !== null && view.t0 !== null ? (view.time - view.t0).toFixed(3) : "0.000";
  $("cursor").textContent = `event ${at} / ${S.total} · t = ${t} s`;
  $("live").textContent = S.info && S.info.live ? "Live" : "End";
  $("live").classList.toggle("on", S.cursor === null);
  for (const fmt of ["svg", "dot", "mermaid"]) {
    $(`export-${fmt}`).href = `/api/export?format=${fmt}&at=${at}`;
  }
}

function applyView(view, force = false) {
  S.view = view;
  S.total = view.total;
  S.first = view.first || 0;
  if (view.structure_version !== S.structureVersion && !force) {
    if (!S.loadingSvg) {
      S.loadingSvg = loadStructure(view.structure_version).then(() => {
        S.loadingSvg = null;
        applyView(S.view, true);
      });
    }
    return;
  }
  if (!force && refocus(view)) return;
  applyGraph(view);
  renderSide(view);
  const status = $("status");
  if (view.running) {
    status.textContent = "running";
    status.className = "pill running";
  } else if (view.root_outcome) {
    status.textContent = `outcome: ${view.root_outcome}`;
    status.className = `pill ${view.root_outcome}`;
  } else {
    status.textContent = view.index ? "stopped" : "not started";
    status.className = "pill";
  }
  const notes = [];
  if (view.resyncs) notes.push(`viewer skipped events ${view.resyncs}× (caught up)`);
  if (view.errors.length) notes.push(`${view.errors.length} error(s)`);
  $("notice").hidden = !notes.length;
  $("notice").textContent = notes.join(" · ");
  document.body.dataset.index = String(view.index);
  updateCursor(view);
  document.dispatchEvent(new CustomEvent("smach:view", { detail: view })); // gantt.js
}

let seekTimer = null;
function seek(n, immediate = false) {
  stopPlay();
  S.cursor = Math.max(S.first, Math.min(n, S.total));
  if (S.cursor === S.total && S.info && S.info.live) S.cursor = null;
  updateCursor(S.view);
  clearTimeout(seekTimer);
  seekTimer = setTimeout(showCursor, immediate ? 0 : 40);
}

async function showCursor() {
  const at = S.cursor === null ? S.total : S.cursor;
  const view = await getJSON(`/api/view?at=${at}`);
  applyView(view);
  await loadTimeline(at);
}

function stopPlay() {
  if (S.playing) clearTimeout(S.playing);
  S.playing = null;
  $("play").textContent = "▶";
}

async function play() {
  if (S.playing) return stopPlay();
  let at = S.cursor === null ? S.first : S.cursor;
  if (at >= S.total) at = S.first;
  const records = await getJSON(`/api/records?start=${at}&end=${S.total}`);
  $("play").textContent = "❚❚";
  let i = 0;
  const step = async () => {
    if (i >= records.length) return stopPlay();
    const r = records[i++];
    S.cursor = r.n + 1;
    const view = await getJSON(`/api/view?at=${S.cursor}`);
    applyView(view);
    appendTimeline([r]);
    const next = records[i];
    const dt = next && typeof next.time === "number" && typeof r.time === "number" ? next.time - r.time : 0.05;
    if (S.playing !== null) S.playing = setTimeout(step, Math.min(1000, Math.max(30, dt * 1000)));
  };
  S.playing = setTimeout(step, 0);
}

// -- live stream ------------------------------------------------------------------------------
function openStream() {
  const source = new EventSource(`/api/stream?since=${S.total}`);
  source.addEventListener("update", (ev) => {
    const msg = JSON.parse(ev.data);
    S.total = msg.view.total;
    S.first = msg.view.first || 0;
    if (S.cursor === null) {
      applyView(msg.view);
      appendTimeline(msg.records);
    } else {
      updateCursor(S.view);
    }
  });
  source.addEventListener("error", () => {
    $("mode").textContent = "disconnected";
    $("mode").className = "pill";
  });
  source.addEventListener("open", () => {
    $("mode").textContent = "live";
    $("mode").className = "pill live";
  });
}

// -- start --------------------------------------------------------------------------------------
async function main() {
  installPanZoom();
  S.info = await getJSON("/api/info");
  document.title = `${S.info.title} · smach viewer`;
  $("title").textContent = S.info.title;
  $("mode").textContent = S.info.live ? "live" : "replay";
  $("mode").className = `pill ${S.info.live ? "live" : "replay"}`;
  $("fit").onclick = fit;
  const focus = document.createElement("button");
  focus.id = "focus";
  focus.textContent = "Focus";
  focus.title = "show the active path large, the rest collapsed (the default)";
  focus.className = "on";
  $("fit").after(focus);
  focus.onclick = () => { setFocus(true); refreshStructure(); };
  $("expand-all").onclick = () => { setFocus(false); S.collapsed.clear(); refreshStructure(); };
  $("collapse-all").onclick = () => {
    setFocus(false);
    for (const el of $("graph").querySelectorAll(".cluster")) if (el.dataset.path !== S.root) S.collapsed.add(el.dataset.path);
    refreshStructure();
  };
  $("slider").addEventListener("input", (ev) => seek(parseInt(ev.target.value, 10)));
  $("back").onclick = () => seek((S.cursor === null ? S.total : S.cursor) - 1, true);
  $("fwd").onclick = () => seek((S.cursor === null ? S.total : S.cursor) + 1, true);
  $("play").onclick = play;
  $("live").onclick = () => seek(S.total, true);
  $("all-events").onchange = () => loadTimeline(S.cursor === null ? S.total : S.cursor);
  $("events").addEventListener("click", (ev) => {
    const tr = ev.target.closest("tr");
    if (tr) seek(parseInt(tr.dataset.n, 10) + 1, true);
  });
  document.addEventListener("keydown", (ev) => {
    if (ev.target.tagName === "INPUT" && ev.target.type !== "range") return;
    if (ev.key === "ArrowLeft") { ev.preventDefault(); $("back").click(); }
    if (ev.key === "ArrowRight") { ev.preventDefault(); $("fwd").click(); }
  });
  window.addEventListener("resize", () => S.vb && setViewBox(S.vb));
  const view = await getJSON("/api/view");
  S.total = view.total;
  S.view = view;
  await loadStructure(view.structure_version);
  applyView(view, true);
  await loadTimeline(S.total);
  if (S.info.live) openStream();
  else S.cursor = null;
  document.body.dataset.ready = "1";
}

// Started once every script of the page has run: control.js, gantt.js, scene.js and
// orders.js listen for "smach:view", and the first view must reach them (a replay gets no
// other). Started at once, the first /api/view could come back before the browser had
// loaded them, as on a busy machine.
function start() {
  main().catch((err) => {
    document.body.dataset.error = String(err);
    console.error(err);
  });
}
if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
else start();
