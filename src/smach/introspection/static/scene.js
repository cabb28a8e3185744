// The scene panel: the picture of the world the machine acts on (a pyrobosim map, say),
// beside the graph. Whoever owns a world emits "scene" records (SVG text; see
// SceneChanged in smach/introspection/events.py); the view only says which one is
// newest at the moment shown (view.scene: its record number n, time, title) and the
// page fetches that picture (/api/scene?n=N) when n changes, never otherwise. The
// panel exists when the run has any scene (view.has_scenes) and can be closed with
// the World button. It listens to the "smach:view" event app.js sends with every view.
"use strict";

(() => {
  const W = { open: true, shown: null, pane: null, button: null, img: null };
  window.smachScene = W;

  function setup() {
    const pane = document.createElement("section");
    pane.id = "scene-pane";
    pane.hidden = true;
    pane.innerHTML =
      '<div id="scene-head"><h2>World</h2><span id="scene-caption"></span>' +
      '<a id="scene-open" target="_blank" rel="noopener" title="the picture on its own, full size">open</a></div>' +
      '<div id="scene-box"><img id="scene-img" alt="picture of the world" hidden>' +
      '<p id="scene-empty" class="empty">no picture of the world yet at this moment</p></div>';
    document.getElementById("graph-pane").after(pane);
    W.pane = pane;
    W.button = window.smachPaneButton(
      "scene-toggle",
      "World",
      "show or hide the picture of the world beside the machine",
      () => {
        W.open = !W.open;
        if (W.view) render(W.view);
      },
    );
    W.button.className = "on";
    W.img = document.getElementById("scene-img");
    W.img.addEventListener("load", () => {
      document.body.dataset.scene = W.img.dataset.n;
    });
  }

  function seconds(t, view) {
    if (typeof t !== "number" || typeof view.t0 !== "number") return "";
    return ` · t = ${(t - view.t0).toFixed(1)} s`;
  }

  function render(view) {
    W.view = view;
    const has = Boolean(view.has_scenes || view.scene);
    const shown = has && W.open;
    W.button.hidden = !has;
    W.button.classList.toggle("on", W.open);
    W.pane.hidden = !shown;
    document.querySelector("main").classList.toggle("with-scene", shown);
    const scene = view.scene;
    document.getElementById("scene-empty").hidden = Boolean(scene);
    W.img.hidden = !scene;
    const open = document.getElementById("scene-open");
    open.hidden = !scene;
    if (!scene) {
      W.shown = null;
      document.getElementById("scene-caption").textContent = "";
      document.body.dataset.scene = "0";
      return;
    }
    document.getElementById("scene-caption").textContent = (scene.title || "") + seconds(scene.time, view);
    if (scene.n !== W.shown) {
      // Only a new picture is fetched: the newest view of a live run carries just its number.
      W.shown = scene.n;
      const url = `/api/scene?n=${scene.n}`;
      W.img.dataset.n = String(scene.n);
      W.img.src = url;
      open.href = url;
    }
  }

  setup();
  document.addEventListener("smach:view", (ev) => render(ev.detail));
})();
