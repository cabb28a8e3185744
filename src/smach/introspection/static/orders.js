// The queue panel: the orders of a mission of orders (plan_bridge's orders,
// docs/orders.md), one row per order: its id, its status in colour, its robots, when
// it arrived and its latency (done), and under it the goal and the reason (failed,
// refused, cancelled). The rows come from the view (view.orders, folded by the server
// from the "order" records: live, replay slider, play), via the "smach:view" event
// app.js sends with every view. With control endpoints whose actions include "order"
// (and the URL's #token=...), a form sends an order and each open order has a Cancel
// button; both are POST /api/control requests, as control.js makes them.
"use strict";

(() => {
  const FINAL = new Set(["done", "failed", "refused", "cancelled"]);
  const O = { view: null, token: null, canOrder: false, live: false, shown: null, section: null };
  window.smachOrders = O;
  const byId = (id) => document.getElementById(id);
  const esc = (text) => String(text).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

  function setup() {
    const section = document.createElement("section");
    section.id = "orders";
    section.hidden = true;
    section.innerHTML =
      '<h2>Orders <span id="orders-count" class="path"></span></h2>' +
      '<form id="order-form" hidden autocomplete="off">' +
      '<input id="order-goal" placeholder="goal: atoms or a goal\'s name" aria-label="goal">' +
      '<input id="order-priority" type="number" step="1" value="0" title="priority: higher first" aria-label="priority">' +
      '<button id="order-send" type="submit">Send order</button></form>' +
      '<div id="order-message"></div>' +
      '<table id="orders-table"><thead><tr><th>order</th><th>status</th><th>robots</th>' +
      '<th title="arrival, seconds of the mission\'s clock">at</th>' +
      '<th title="arrival to done, seconds of the mission\'s clock">latency</th><th></th></tr></thead>' +
      "<tbody></tbody></table>" +
      '<p id="orders-empty" class="empty">no order yet</p>';
    const side = byId("side");
    side.insertBefore(section, byId("selection"));
    O.section = section;
    byId("order-form").addEventListener("submit", (ev) => {
      ev.preventDefault();
      const goal = byId("order-goal").value.trim();
      if (!goal) return message("give a goal: atoms like (at r1 office) or a goal's name", true);
      const priority = parseInt(byId("order-priority").value || "0", 10);
      send({ action: "order", goal, priority: Number.isFinite(priority) ? priority : 0 }).then((data) => {
        if (data) {
          message(`order ${data.id} sent: ${data.goal}`, false);
          byId("order-goal").value = "";
        }
      });
    });
    // One listener for every row's button: rows are redrawn as the orders change.
    byId("orders-table").addEventListener("click", (ev) => {
      const button = ev.target.closest("button[data-cancel]");
      if (!button) return;
      const id = button.dataset.cancel;
      button.disabled = true;
      send({ action: "cancel", id }).then((data) => {
        if (data) message(`order ${id} ${data.status}`, false);
      });
    });
  }

  function message(text, isError) {
    const box = byId("order-message");
    box.textContent = text;
    box.className = isError ? "ctl-error" : "";
  }

  // POST an order request; its data (the reply's "data"), or null (the error shown).
  async function send(body) {
    if (!O.token) return null;
    try {
      const r = await fetch("/api/control", {
        method: "POST",
        headers: { "Content-Type": "application/json", "X-Control-Token": O.token },
        body: JSON.stringify({ ...body, source: "viewer" }),
        cache: "no-store",
      });
      const data = await r.json();
      if (!r.ok) {
        message(data.error || `error ${r.status}`, true);
        return null;
      }
      return data.data || {};
    } catch (err) {
      message(String(err), true);
      return null;
    }
  }

  function seconds(t) {
    return typeof t === "number" ? t.toFixed(1) : "";
  }

  function latency(order) {
    if (order.status !== "done" || typeof order.latency !== "number") return "";
    return `${order.latency.toFixed(1)} s`;
  }

  // Two rows an order: its figures, then its goal and the reason (failed, refused, cancelled).
  function rows(order, cancellable) {
    const priority = order.priority ? ` <span class="oprio" title="priority">p${esc(order.priority)}</span>` : "";
    const cancel = cancellable && !FINAL.has(order.status)
      ? `<button data-cancel="${esc(order.id)}" title="cancel order ${esc(order.id)}">Cancel</button>`
      : "";
    const reason = order.reason ? ` <span class="oreason">${esc(order.reason)}</span>` : "";
    return `<tr class="ohead" data-order="${esc(order.id)}" data-status="${esc(order.status)}">` +
      `<td class="oid"><b>${esc(order.id)}</b>${priority}</td>` +
      `<td><span class="ost s-${esc(order.status)}">${esc(order.status)}</span></td>` +
      `<td class="orob">${esc((order.robots || []).join(", "))}</td>` +
      `<td class="oat">${esc(seconds(order.arrived))}</td>` +
      `<td class="olat">${esc(latency(order))}</td>` +
      `<td class="octl">${cancel}</td></tr>` +
      `<tr class="odetail" data-detail="${esc(order.id)}" data-status="${esc(order.status)}">` +
      `<td colspan="6"><span class="ogoal">${esc(order.goal)}</span>${reason}</td></tr>`;
  }

  function render(view) {
    O.view = view;
    const orders = view.orders || [];
    O.section.hidden = !orders.length && !O.canOrder;
    if (O.section.hidden) return;
    // Controls act on the run now: none while the slider shows the past.
    const now = O.live && (window.smachViewer || {}).cursor == null;
    byId("order-form").hidden = !(O.canOrder && now);
    const cancellable = O.canOrder && now && Boolean(O.token);
    const key = JSON.stringify([orders, cancellable]);
    if (key === O.shown) return;
    O.shown = key;
    const open = orders.filter((o) => !FINAL.has(o.status)).length;
    byId("orders-count").textContent = orders.length ? `${orders.length} · ${open} open` : "";
    byId("orders-empty").hidden = orders.length > 0;
    byId("orders-table").hidden = !orders.length;
    byId("orders-table").tBodies[0].innerHTML = orders.map((o) => rows(o, cancellable)).join("");
    document.body.dataset.orders = String(orders.length);
  }

  async function start() {
    const info = await window.smachServer.info();
    if (!info) return;
    O.live = Boolean(info.live);
    if (info.controls) {
      try {
        const status = await (await fetch("/api/control", { cache: "no-store" })).json();
        O.canOrder = Boolean(status.enabled && (status.actions || []).includes("order"));
      } catch (err) {
        O.canOrder = false;
      }
    }
    O.token = window.smachServer.token();
    if (O.canOrder && !O.token) {
      for (const el of byId("order-form").elements) el.disabled = true;
      message("read-only: open the URL with its #token=... to send orders", true);
    }
    O.shown = null;
    if (O.view) render(O.view);
  }

  setup();
  document.addEventListener("smach:view", (ev) => render(ev.detail));
  start();
})();
