// The Gantt view of temporal plans: one row per started action, its planned interval
// (outlined) and its actual one (filled, coloured by outcome; a running action grows).
// The server folds the rows (/api/gantt, see smach/introspection/gantt.py; the view
// itself only says how many there are); this file only draws them. It listens to the
// "smach:view" event app.js sends with every view (live, replay slider, play) and,
// while the Gantt is open, fetches the rows of that moment.
"use strict";

(() => {
  const SVGNS = "http://www.w3.org/2000/svg";
  const ROW = 22;
  const LABEL = 290;
  const PAD = 16;
  const G = {
    view: null, data: null, at: 0, open: false, timer: null, pane: null, button: null,
    loading: false, wanted: null, shown: null,
  };
  window.smachGantt = G;

  function el(name, attrs, parent) {
    const node = document.createElementNS(SVGNS, name);
    for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, String(v));
    if (parent) parent.appendChild(node);
    return node;
  }

  function esc(text) {
    return String(text).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
  }

  // Round tick steps (1, 2, 5 x 10^n) giving about `count` ticks over [0, max].
  function ticks(max, count) {
    if (!(max > 0)) return [0];
    const raw = max / count;
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || raw;
    const out = [];
    for (let t = 0; t <= max + step * 1e-9; t += step) out.push(Number(t.toPrecision(12)));
    return out;
  }

  function fmt(t) {
    const a = Math.abs(t);
    if (a === 0) return "0";
    if (a < 0.01) return t.toPrecision(2);
    if (a < 10) return t.toFixed(a < 1 ? 3 : 2).replace(/\.?0+$/, "");
    return t.toFixed(1).replace(/\.0$/, "");
  }

  // The label, cut (with "…") to fit `room` pixels of the label column.
  const fitted = new Map(); // text -> what fits (measuring forces a layout: once per text)
  function fitLabel(node, text, room) {
    const known = fitted.get(text);
    if (known !== undefined) {
      node.textContent = known;
      return;
    }
    node.textContent = text;
    let width = node.getComputedTextLength();
    let keep = text.length;
    while (width > room && keep > 4) {
      keep = Math.min(keep - 1, Math.floor((keep * room) / width) - 1);
      node.textContent = `${text.slice(0, keep)}…`;
      width = node.getComputedTextLength();
    }
    if (fitted.size > 20000) fitted.clear();
    fitted.set(text, node.textContent);
  }

  function setup() {
    const bar = document.getElementById("bar");
    const pane = document.createElement("section");
    pane.id = "gantt-pane";
    pane.hidden = true;
    pane.innerHTML =
      '<div id="gantt-head"><div id="gantt-note"></div><div class="gantt-legend">' +
      '<span><i class="gsw planned"></i>planned</span>' +
      '<span><i class="gsw succeeded"></i>succeeded</span>' +
      '<span><i class="gsw running"></i>running</span>' +
      '<span><i class="gsw aborted"></i>aborted / invalid</span>' +
      '<span><i class="gsw preempted"></i>preempted</span>' +
      '<span><i class="gsw interrupted"></i>interrupted (run killed, then resumed)</span></div>' +
      '<svg id="gantt-axis"></svg></div><div id="gantt-scroll"><svg id="gantt-chart"></svg></div>';
    document.getElementById("graph-pane").appendChild(pane);
    G.pane = pane;
    G.button = window.smachPaneButton(
      "gantt-toggle",
      "Gantt",
      "timeline of the temporal plan: planned vs actual start and end of each action",
      () => toggle(!G.open),
    );
    window.addEventListener("resize", () => G.open && draw());
  }

  function toggle(open) {
    G.open = open;
    G.pane.hidden = !open;
    G.button.classList.toggle("on", open);
    if (open && G.view) load(G.view.index);
  }

  // The rows at record `index` (/api/gantt): one request at a time, the newest wanted.
  async function load(index) {
    G.wanted = index;
    if (G.loading) return;
    G.loading = true;
    try {
      while (G.wanted !== null && G.wanted !== G.shown) {
        const at = G.wanted;
        const r = await fetch(`/api/gantt?at=${at}`, { cache: "no-store" });
        if (!r.ok) throw new Error(`/api/gantt: ${r.status}`);
        G.data = await r.json();
        G.at = performance.now();
        G.shown = at;
        if (G.open) draw();
      }
    } finally {
      G.loading = false;
    }
  }

  // While a live run shows its newest view, running bars keep growing between views.
  function live() {
    const S = window.smachViewer;
    return Boolean(S && S.info && S.info.live && S.cursor === null && G.view && G.view.running);
  }

  function render(view) {
    G.view = view;
    const rows = view.gantt ? view.gantt.rows : 0;
    G.button.hidden = !rows;
    G.button.textContent = rows ? `Gantt (${rows})` : "Gantt";
    document.body.dataset.ganttRows = String(rows);
    if (!rows && G.open) toggle(false);
    if (G.open) load(view.index);
    clearInterval(G.timer);
    G.timer = live() ? setInterval(() => (live() ? draw() : clearInterval(G.timer)), 200) : null;
  }

  function draw() {
    const gantt = G.data;
    const chart = document.getElementById("gantt-chart");
    const axis = document.getElementById("gantt-axis");
    chart.innerHTML = "";
    axis.innerHTML = "";
    if (!gantt) return;
    const wallAxis = gantt.axis === "wall";
    // Seconds since the view arrived, on the actual axis (live growth of running bars).
    let extra = live() ? (performance.now() - G.at) / 1000 : 0;
    if (!wallAxis && gantt.time_scale > 0) extra /= gantt.time_scale;
    const rows = gantt.rows
      .map((r) => (r.running ? { ...r, a1: r.a1 + extra } : r))
      .sort((x, y) => x.dispatch - y.dispatch || x.p0 - y.p0 || x.index - y.index);
    const width = Math.max(480, G.pane.clientWidth - 18);
    const span = width - LABEL - PAD * 2;
    const planMax = Math.max(1e-9, ...rows.map((r) => r.p1));
    const actMax = Math.max(1e-9, ...rows.map((r) => r.a1));
    const px = wallAxis ? (t) => LABEL + PAD + (t / planMax) * span : null;
    const both = Math.max(planMax, actMax);
    const X = wallAxis ? px : (t) => LABEL + PAD + (t / both) * span;
    const AX = wallAxis ? (t) => LABEL + PAD + (t / actMax) * span : X;

    const note = document.getElementById("gantt-note");
    if (wallAxis) {
      note.innerHTML =
        "Run as fast as it goes (time scale 0): <b>planned</b> bars on the <b>plan seconds</b> axis, " +
        "<b>actual</b> bars on the <b>wall seconds</b> axis below it; each axis spans the width.";
    } else {
      note.innerHTML =
        `Axis in <b>plan seconds</b>; actual times = wall seconds ÷ time scale ${esc(fmt(gantt.time_scale))} ` +
        `(1 plan s = ${esc(fmt(gantt.time_scale))} wall s). ${gantt.dispatches} dispatch(es): a replan or retry starts a new one.`;
    }

    // Axes (sticky above the scrolling rows).
    const axisH = wallAxis ? 44 : 24;
    axis.setAttribute("width", width);
    axis.setAttribute("height", axisH);
    const axes = wallAxis
      ? [[X, planMax, "plan s", 2], [AX, actMax, "wall s", 24]]
      : [[X, both, "plan s", 2]];
    for (const [scale, max, unit, y] of axes) {
      el("text", { x: LABEL - 6, y: y + 13, class: "gantt-unit", "text-anchor": "end" }, axis).textContent = unit;
      for (const t of ticks(max, Math.max(2, Math.floor(span / 90)))) {
        const x = scale(t);
        el("line", { x1: x, x2: x, y1: y + 14, y2: y + 19, class: "gantt-tick" }, axis);
        el("text", { x, y: y + 11, class: "gantt-tick-label", "text-anchor": "middle" }, axis).textContent = fmt(t);
      }
    }

    // Rows.
    const height = rows.length * ROW + 8;
    chart.setAttribute("width", width);
    chart.setAttribute("height", height);
    for (const t of ticks(wallAxis ? actMax : both, Math.max(2, Math.floor(span / 90)))) {
      const x = AX(t);
      el("line", { x1: x, x2: x, y1: 0, y2: height, class: "gantt-grid" }, chart);
    }
    let lastDispatch = null;
    rows.forEach((r, i) => {
      const y = i * ROW + 4;
      const g = el("g", {
        class: `gantt-row o-${r.outcome}`,
        "data-index": r.index,
        "data-outcome": r.outcome,
        "data-dispatch": r.dispatch,
      }, chart);
      if (i % 2) el("rect", { x: 0, y: y - 2, width, height: ROW, class: "gantt-stripe" }, g);
      const boundary = lastDispatch !== null && r.dispatch !== lastDispatch;
      if (boundary) el("line", { x1: 0, x2: width, y1: y - 2, y2: y - 2, class: "gantt-dispatch" }, g);
      lastDispatch = r.dispatch;
      const label = el("text", { x: 6, y: y + 13, class: "gantt-label" }, g);
      fitLabel(label, `${r.index}. ${r.action}`, LABEL - 12);
      const p0 = X(r.p0);
      const planned = el("rect", {
        x: p0, y: y + 1, width: Math.max(1, X(r.p1) - p0), height: ROW - 6, rx: 2, class: "gantt-planned",
      }, g);
      const a0 = AX(r.a0);
      const actual = el("rect", {
        x: a0, y: y + 5, width: Math.max(2, AX(r.a1) - a0), height: ROW - 14, rx: 2, class: `gantt-actual o-${r.outcome}`,
      }, g);
      if (boundary) {
        // Over the bars: which plan this block of rows runs.
        el("text", { x: width - 6, y: y + 9, class: "gantt-plan", "text-anchor": "end" }, g).textContent =
          `plan #${r.plan}, dispatch ${r.dispatch + 1}`;
      }
      const unit = wallAxis ? "wall s" : "plan s";
      const tip =
        `${r.index}. ${r.action} (plan #${r.plan}) — ${r.outcome}\n` +
        `planned: ${fmt(r.p0)} → ${fmt(r.p1)} plan s (start ${fmt(r.planned_start)} in its plan, duration ${fmt(r.planned_duration)})\n` +
        `actual: ${fmt(r.a0)} → ${r.running ? "…" : fmt(r.a1)} ${unit}` +
        (wallAxis ? "" : ` (late by ${fmt(r.a1 - r.p1)} at the end)`);
      el("title", {}, planned).textContent = tip;
      el("title", {}, actual).textContent = tip;
      el("title", {}, label).textContent = tip;
    });
    if (rows.some((r) => r.running)) {
      const now = AX(Math.max(...rows.map((r) => r.a1)));
      el("line", { x1: now, x2: now, y1: 0, y2: height, class: "gantt-now" }, chart);
    }
    document.body.dataset.ganttDrawn = String(rows.length);
  }

  setup();
  document.addEventListener("smach:view", (ev) => render(ev.detail));
})();
