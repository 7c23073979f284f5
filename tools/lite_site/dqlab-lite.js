// The status line of the in-browser chapters: what is loading, how much, how far, then
// "ready". It is part of the notebook page from its first paint (tools/lite.py adds the line
// and this script to notebooks/index.html) and follows the kernel's start:
//
// * the notebook application loads (JupyterLite, its scripts);
// * the kernel's worker starts Python (static/pyodide/dqlab-pyodide.js): it asks this page
//   which chapter it runs, and reports the bytes it loads, from the network or from the
//   browser's cache, and the modules it imports;
// * Python is ready when the kernel says it is idle.
//
// The worker's messages are {dqlabLite: {...}}; the page answers its question with the
// chapter's notebook name, read from the page's address (?path=...).
(function () {
  "use strict";

  const TAG = "dqlabLite";
  const READY_SHOWN_MS = 20000;                       // how long "ready" stays on screen
  const started = performance.now();
  const notebook = new URLSearchParams(window.location.search).get("path");
  const state = { phase: "app", total: 0, loaded: 0, warm: false, manifest: null,
                  problems: [], imported: false, ready: false };

  function seconds() {
    return Math.round((performance.now() - started) / 100) / 10;
  }

  function megabytes(bytes) {
    return (bytes / 1e6).toFixed(bytes < 1e7 ? 1 : 0) + " MB";
  }

  function chapter() {
    const manifest = state.manifest;
    return (manifest && notebook && manifest.notebooks[notebook]) || null;
  }

  function words(list) {
    return list.length < 2 ? list.join("") :
      list.slice(0, -1).join(", ") + " and " + list[list.length - 1];
  }

  // --- the status line ------------------------------------------------------------------

  function element(id) {
    return document.getElementById(id);
  }

  function show(text, fraction, detail) {
    const box = element("dqlab-lite-status");
    if (!box) {
      return;
    }
    const message = element("dqlab-lite-message");
    if (message.textContent !== text) {
      message.textContent = text;                      // a change of phase is announced
    }
    const bar = element("dqlab-lite-progress");
    const percent = element("dqlab-lite-percent");
    if (fraction === null) {
      bar.removeAttribute("value");                    // indeterminate
      percent.textContent = "";
    } else {
      bar.value = Math.max(0, Math.min(1, fraction));
      percent.textContent = Math.round(100 * bar.value) + " %";
    }
    element("dqlab-lite-detail").textContent = detail || "";
    box.dataset.phase = state.phase;
  }

  function update() {
    const info = chapter();
    const name = info ? info.title : "this chapter";
    if (state.phase === "app") {
      show("Opening " + name + " in your browser: loading the notebook application…", null,
           "");
    } else if (state.phase === "runtime") {
      const size = megabytes(state.total);
      const where = state.warm ? size + " from this browser's cache" :
        size + ", downloaded on the first visit only";
      show("Starting Python in your browser — " + where, state.total ?
           state.loaded / state.total : null, megabytes(state.loaded) + " of " + size);
    } else if (state.phase === "imports") {
      const modules = [];
      for (const name of info ? info.modules : ["numpy", "matplotlib", "dqlab"]) {
        const top = name.split(".")[0];
        if (!modules.includes(top)) {
          modules.push(top);
        }
      }
      show("Importing " + words(modules) + "…", 1, "");
    } else if (state.phase === "error") {
      show("Python could not start in this browser: " + state.error + ". Reloading the page " +
           "starts it again.", null, "");
    } else if (state.phase === "ready") {
      const skipped = info && info.skipped ? " " + info.skipped : "";
      const problems = state.problems.length ?
        " Some modules could not be imported: " + state.problems.join("; ") + "." : "";
      show("Python is ready (started in " + state.readyAfter + " s). Run a cell with " +
           "Shift+Enter, or every cell with Run ▸ Run All Cells." + skipped + problems, 1, "");
      const close = element("dqlab-lite-close");
      if (close) {
        close.hidden = false;
      }
    }
  }

  // --- the kernel's worker ----------------------------------------------------------------

  function onWorkerMessage(worker, event) {
    const data = event.data && event.data[TAG];
    if (!data) {
      return;
    }
    if (data.event === "hello") {                      // a kernel starts (or restarts)
      worker.postMessage({ [TAG]: { notebook: notebook } });
      state.phase = "runtime";
      state.imported = state.ready = false;
      state.loaded = 0;
      const box = element("dqlab-lite-status");
      if (box) {
        box.hidden = false;
      }
    } else if (data.event === "phase" && data.phase === "runtime") {
      state.phase = "runtime";
      state.total = data.total;
      state.warm = data.warm;
    } else if (data.event === "progress") {
      state.loaded = data.loaded;
      state.total = Math.max(state.total, data.total);
    } else if (data.event === "phase" && data.phase === "imports") {
      state.phase = "imports";
    } else if (data.event === "error") {
      state.phase = "error";
      state.error = data.message;
    } else if (data.event === "phase" && data.phase === "imported") {
      state.imported = true;
      state.problems = data.problems || [];
      waitForKernel();
    }
    if (!state.ready) {
      update();
    }
  }

  const NativeWorker = window.Worker;
  if (NativeWorker) {
    window.Worker = class extends NativeWorker {
      constructor(url, options) {
        super(url, options);
        const worker = this;
        this.addEventListener("message", function (event) { onWorkerMessage(worker, event); });
      }
    };
  }

  // The kernel is ready when the application says it is up, idle or already running a cell
  // (or, if the application is not exposed to the page, when the worker has imported the
  // chapter's modules).
  function kernelStatus() {
    const app = window.jupyterapp;
    if (!app || !app.shell) {
      return undefined;
    }
    const widget = app.shell.currentWidget;
    const session = widget && widget.sessionContext && widget.sessionContext.session;
    return session && session.kernel ? session.kernel.status : null;
  }

  function waitForKernel() {
    const status = kernelStatus();
    if (status === "idle" || status === "busy" || (status === undefined && state.imported)) {
      state.phase = "ready";
      state.ready = true;
      state.readyAfter = seconds();
      document.documentElement.dataset.dqlabKernel = "ready";
      update();
      // the line steps aside after a while (the notebook's own kernel indicator stays);
      // not while the reader is on it
      const box = element("dqlab-lite-status");
      setTimeout(function hide() {
        if (box.matches(":hover, :focus-within")) {
          setTimeout(hide, 5000);
        } else if (state.ready) {                     // not if the kernel restarts meanwhile
          box.hidden = true;
        }
      }, READY_SHOWN_MS);
      return;
    }
    setTimeout(waitForKernel, 200);
  }

  // --- start --------------------------------------------------------------------------------

  function start() {
    const close = element("dqlab-lite-close");
    if (close) {
      close.addEventListener("click", function () {
        element("dqlab-lite-status").hidden = true;
      });
    }
    const config = document.getElementById("jupyter-config-data");
    const root = (config && config.dataset.jupyterLiteRoot) || "..";
    fetch(root + "/static/pyodide/dqlab-lite.json")
      .then(function (response) { return response.ok ? response.json() : null; })
      .then(function (manifest) {
        state.manifest = manifest;
        if (!state.ready) {
          update();
        }
      })
      .catch(function () { /* the line keeps its general words */ });
    update();
  }

  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", start);
  } else {
    start();
  }
})();
