// implgen view: Save mesh. Asks the server for a closed STL of the shape the page shows (its param values and its
// clip, read from the page as a render request reads them), says how it goes beside the button, and hands the
// file to the browser. The server checks everything (view/meshsave.py). app.js calls attach() once, message()
// for each {"type": "mesh"} message, received() with the STL's bytes, and reset() when the socket closes.
// Plain JS, no build step.
"use strict";

window.implgenMesh = (() => {
  const $ = (id) => document.getElementById(id);
  let api = null; // { send, showMessage, download } from app.js
  let running = false;
  let name = "surface.stl";
  let text = "";
  let started = 0;
  let ticker = 0;

  function show() {
    const seconds = Math.floor((performance.now() - started) / 1000);
    $("mesh-status").textContent = running ? `${text}... ${seconds} s` : "";
  }

  function setRunning(on) {
    running = on;
    const button = $("save-mesh");
    button.textContent = on ? "Stop meshing" : "Save mesh";
    button.dataset.state = on ? "running" : "idle";
    $("mesh-cells").disabled = on;
    clearInterval(ticker);
    if (on) {
      started = performance.now();
      ticker = setInterval(show, 500);
    }
    show();
  }

  function click() {
    if (running) { api.send({ type: "stop_mesh" }); return; }
    const view = window.implgenState(); // the values and options a render request would send now
    text = "asking the server";
    setRunning(true);
    api.send({ type: "save_mesh", cells: Number($("mesh-cells").value), values: view.values, options: view.options });
  }

  function message(msg) {
    if (msg.state === "running") {
      name = String(msg.name || "surface.stl");
      text = String(msg.text);
      if (!running) setRunning(true); else show();
      return;
    }
    setRunning(false);
    if (msg.state === "failed") api.showMessage(String(msg.text), true);
    else api.showMessage(String(msg.text), false); // done: what the file holds; stopped: said so
  }

  function reset() { // the socket closed: no mesh is coming
    if (running) setRunning(false);
  }

  function received(bytes) {
    api.download(new Blob([bytes], { type: "model/stl" }), name);
  }

  function attach(a) {
    api = a;
    $("save-mesh").addEventListener("click", click);
  }

  return { attach, message, received, reset };
})();
