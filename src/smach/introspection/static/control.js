// Control panel of the smach viewer (pause, resume, step, preempt, force outcome,
// breakpoints, and mission actions when the server offers them). Shown only when
// the server has control endpoints (/api/info "controls": true). Actions need the
// per-run token from the URL fragment (#token=...); without it the panel is read-only.
"use strict";

(function () {
  const C = { token: null, status: null, enabled: false, busy: false };
  const byId = (id) => document.getElementById(id);
  const escText = (text) => String(text).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
  const viewer = () => window.smachViewer || {};

  function button(id, text, title, onClick) {
    const b = document.createElement("button");
    b.id = id;
    b.textContent = text;
    b.title = title;
    b.addEventListener("click", onClick);
    return b;
  }

  function build(actions) {
    const style = document.createElement("style");
    style.textContent =
      "#control-bar{display:inline-flex;gap:4px;align-items:center}" +
      "#control-state[data-state=paused],#control-state[data-state=at_breakpoint]{background:#fde68a}" +
      "#control .ctl-row{margin:4px 0}.ctl-error{color:#b91c1c}#ctl-history{font-size:12px;margin:4px 0 0 1em;padding:0}" +
      "#ctl-history .src{color:#666}" +
      ".ctl-bp-node>rect:first-of-type{stroke:#dc2626!important;stroke-width:3px!important}" +
      ".ctl-held-node>rect:first-of-type{stroke-dasharray:6 3;fill:#fef3c7!important}";
    document.head.appendChild(style);
    const bar = document.createElement("span");
    bar.id = "control-bar";
    const pill = document.createElement("span");
    pill.id = "control-state";
    pill.className = "pill";
    pill.textContent = "control: …";
    bar.appendChild(pill);
    bar.appendChild(button("ctl-pause", "Pause", "hold every container at its next transition", () => send({ action: "pause" })));
    bar.appendChild(button("ctl-resume", "Resume", "let held states start", () => send({ action: "resume" })));
    bar.appendChild(button("ctl-step", "Step", "let one state start, then pause again", () => send({ action: "step" })));
    bar.appendChild(button("ctl-preempt", "Preempt", "ask the whole tree to stop", () => send({ action: "preempt" })));
    const header = byId("bar");
    header.insertBefore(bar, header.querySelector(".spacer"));

    const side = document.createElement("section");
    side.id = "control";
    side.innerHTML =
      '<h2>Control <span id="ctl-path" class="path"></span></h2>' +
      '<div class="ctl-row"><button id="ctl-bp">Toggle breakpoint</button> ' +
      '<input id="ctl-pattern" placeholder="or a pattern, e.g. */PICK" size="18"> ' +
      '<button id="ctl-bp-pattern">Set</button></div>' +
      '<div class="ctl-row"><select id="ctl-outcome"></select> ' +
      '<button id="ctl-force">Force outcome</button></div>' +
      '<div id="ctl-mission" class="ctl-row" hidden>' +
      '<button id="ctl-skip-fx" title="mark the running step done and apply its effects">Skip step (apply effects)</button> ' +
      '<button id="ctl-skip" title="mark the running step done, belief unchanged">Skip step (no effects)</button> ' +
      '<button id="ctl-replan">Replan now</button> <button id="ctl-abort">Abort mission</button><br>' +
      '<input id="ctl-goal" placeholder="(at robot1 kitchen) ..." size="28"> <button id="ctl-goal-set">Change goal</button></div>' +
      '<div id="ctl-breakpoints" class="ctl-row"></div>' +
      '<div id="ctl-message" class="ctl-row"></div>' +
      '<ol id="ctl-history"></ol>';
    const aside = byId("side");
    aside.insertBefore(side, aside.firstChild);
    byId("ctl-bp").addEventListener("click", () => {
      const path = viewer().selected;
      if (path) send({ action: "toggle_breakpoint", pattern: path });
    });
    byId("ctl-bp-pattern").addEventListener("click", () => {
      const pattern = byId("ctl-pattern").value.trim();
      if (pattern) send({ action: "toggle_breakpoint", pattern });
    });
    byId("ctl-force").addEventListener("click", () => {
      const choice = byId("ctl-outcome").value;
      if (!choice) return;
      const [path, outcome] = JSON.parse(choice);
      send({ action: "force_outcome", path, outcome });
    });
    if (actions.includes("skip")) {
      byId("ctl-mission").hidden = false;
      byId("ctl-skip-fx").addEventListener("click", () => send({ action: "skip", apply_effects: true }));
      byId("ctl-skip").addEventListener("click", () => send({ action: "skip", apply_effects: false }));
      byId("ctl-replan").addEventListener("click", () => send({ action: "replan" }));
      byId("ctl-abort").addEventListener("click", () => send({ action: "abort" }));
      byId("ctl-goal-set").addEventListener("click", () => send({ action: "goal", goal: byId("ctl-goal").value }));
    }
    if (!C.token) {
      for (const b of document.querySelectorAll("#control-bar button, #control button")) b.disabled = true;
      message("read-only: open the URL with its #token=... to control the run", true);
    }
  }

  function message(text, isError) {
    const box = byId("ctl-message");
    if (!box) return;
    box.textContent = text;
    box.className = "ctl-row" + (isError ? " ctl-error" : "");
  }

  async function send(body) {
    if (!C.token) return;
    try {
      const r = await fetch("/api/control", {
        method: "POST",
        headers: { "Content-Type": "application/json", "X-Control-Token": C.token },
        body: JSON.stringify(body),
        cache: "no-store",
      });
      const data = await r.json();
      if (!r.ok) message(data.error || `error ${r.status}`, true);
      else message(`${body.action}: ok`, false);
    } catch (err) {
      message(String(err), true);
    }
    poll();
  }

  function render(st) {
    const pill = byId("control-state");
    pill.textContent = "control: " + st.describe;
    pill.dataset.state = st.state;
    const S = viewer();
    byId("ctl-path").textContent = S.selected || "";
    const marks = [["ctl-bp-node", st.matching || []], ["ctl-held-node", st.held || []]];
    const nodes = S.nodes || new Map();
    for (const [cls, paths] of marks) {
      for (const el of document.querySelectorAll("." + cls)) el.classList.remove(cls);
      for (const path of paths) {
        const el = nodes.get(path);
        if (el) el.classList.add(cls);
      }
    }
    const select = byId("ctl-outcome");
    const options = [];
    for (const [path, outcomes] of Object.entries(st.outcomes || {})) {
      for (const outcome of outcomes) options.push([path, outcome]);
    }
    const wanted = JSON.stringify(options);
    if (select.dataset.options !== wanted) {
      select.dataset.options = wanted;
      select.innerHTML = options.length
        ? options.map((o) => `<option value="${escText(JSON.stringify(o))}">${escText(o[0].split("/").pop())} → ${escText(o[1])}</option>`).join("")
        : '<option value="">(no running state)</option>';
    }
    byId("ctl-breakpoints").innerHTML = (st.breakpoints || []).length
      ? "breakpoints: " + st.breakpoints.map((b) => `<code>${escText(b)}</code>`).join(" ")
      : "no breakpoints";
    byId("ctl-history").innerHTML = (st.history || []).slice(-6).reverse()
      .map((h) => `<li>${escText(h.action)} <span class="src">${escText(h.source)}</span> ${escText(h.path || "")}</li>`).join("");
  }

  async function poll() {
    if (C.busy) return;
    C.busy = true;
    try {
      const r = await fetch("/api/control", { cache: "no-store" });
      const st = await r.json();
      if (st.enabled) {
        C.status = st;
        render(st);
      }
    } catch (err) {
      /* the run may have ended; keep the last state on screen */
    } finally {
      C.busy = false;
    }
  }

  // -- replay: the control state recorded in the journal at the moment shown ------------------
  const R = { key: null, busy: false };

  async function replayPoll() {
    const S = viewer();
    const end = S.cursor == null ? S.total : S.cursor;
    const key = `${end}`;
    if (R.busy || key === R.key || !end) return;
    R.busy = true;
    R.key = key;
    try {
      const records = await (await fetch(`/api/records?start=${Math.max(0, end - 2000)}&end=${end}`, { cache: "no-store" })).json();
      let last = null;
      for (const r of records) if (r.kind === "control") last = r;
      let pill = byId("control-replay");
      if (!last && !pill) return;
      if (!pill) {
        pill = document.createElement("span");
        pill.id = "control-replay";
        pill.className = "pill";
        const header = byId("bar");
        header.insertBefore(pill, header.querySelector(".spacer"));
      }
      pill.textContent = last
        ? `control: ${last.state.replace("_", " ")}${last.action === "breakpoint_hit" ? " " + last.path : ""} (last: ${last.action} from ${last.source})`
        : "control: running";
      pill.dataset.state = last ? last.state : "running";
    } catch (err) {
      /* no records yet */
    } finally {
      R.busy = false;
    }
  }

  async function start() {
    const info = await window.smachServer.info();
    if (!info) return;
    if (!info.controls) {
      // A journal (or a run without controls): show the recorded control state, if any.
      setInterval(replayPoll, 500);
      return;
    }
    C.enabled = true;
    C.token = window.smachServer.token();
    const first = await (await fetch("/api/control", { cache: "no-store" })).json();
    build(first.actions || []);
    render(first);
    setInterval(poll, 400);
  }

  window.smachControl = C;
  start();
})();
