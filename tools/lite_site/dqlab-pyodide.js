// The book's start of Python in the in-browser kernel (the Pyodide kernel's web worker).
//
// The kernel is configured (jupyter-lite.json, "pyodideUrl") to load this script instead of
// pyodide.js. It defines loadPyodide, which the kernel calls at once when a notebook opens:
//
// 1. It asks the notebook's page which chapter this kernel runs (the page answers from the
//    address, ?path=...), and reads in dqlab-lite.json (written when the site is built) what
//    that chapter imports.
// 2. It loads Pyodide with the kernel's packages and the chapter's, all at once, and none
//    that neither uses (the kernel would install ssl, sqlite3 and jedi one after the other).
// 3. It imports the kernel's modules and the chapter's (numpy, matplotlib, dqlab, ...), so
//    that the first cell the reader runs finds them imported.
// 4. Every file it downloads is kept in the browser's Cache Storage under the site's build
//    (a second visit, even offline, reads them from there), and the page is told what is
//    loading, how many bytes of how many, and when Python is ready; the page shows it.
//
// Messages to the page are {dqlabLite: {...}}; the kernel's own messages to its page carry
// other keys and are left alone.
(function () {
  "use strict";

  const TAG = "dqlabLite";
  const CACHE_PREFIX = "dqlab-lite-";

  function tell(message) {
    try {
      self.postMessage({ [TAG]: message });
    } catch (error) {
      // a page that cannot receive the message has nothing to show
    }
  }

  // The chapter of this kernel, from the page that started it (null if it does not say).
  function askNotebook(timeoutMs) {
    return new Promise(function (resolve) {
      const timer = setTimeout(function () { done(null); }, timeoutMs);
      function done(value) {
        clearTimeout(timer);
        self.removeEventListener("message", listen);
        resolve(value);
      }
      function listen(event) {
        const data = event.data && event.data[TAG];
        if (data && "notebook" in data) {
          done(data.notebook);
        }
      }
      self.addEventListener("message", listen);
      tell({ event: "hello" });
    });
  }

  // --- downloads: counted for the page, and kept in Cache Storage ------------------------

  const realFetch = self.fetch.bind(self);
  const progress = { loaded: 0, total: 0, cached: 0, fetched: 0, last: 0 };

  function report(force) {
    const now = Date.now();
    if (force || now - progress.last > 150) {
      progress.last = now;
      tell({ event: "progress", loaded: progress.loaded, total: progress.total,
             cached: progress.cached, fetched: progress.fetched });
    }
  }

  async function openCache(name) {
    try {
      const names = await caches.keys();
      await Promise.all(names.filter(function (n) {
        return n.startsWith(CACHE_PREFIX) && n !== name;
      }).map(function (n) { return caches.delete(n); }));  // earlier builds of the site
      return await caches.open(name);
    } catch (error) {
      return null;                                         // no Cache Storage: no caching
    }
  }

  // The response's bytes, counted as they arrive.
  async function counted(response) {
    if (!response.body) {
      const buffer = await response.arrayBuffer();
      progress.loaded += buffer.byteLength;
      report(false);
      return buffer;
    }
    const reader = response.body.getReader();
    const chunks = [];
    let size = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) {
        break;
      }
      chunks.push(value);
      size += value.byteLength;
      progress.loaded += value.byteLength;
      report(false);
    }
    const bytes = new Uint8Array(size);
    let offset = 0;
    for (const chunk of chunks) {
      bytes.set(chunk, offset);
      offset += chunk.byteLength;
    }
    return bytes.buffer;
  }

  // Whether cached bytes still have the sha256 that Pyodide's lock gives them (if it gives one).
  async function intact(buffer, integrity) {
    if (!integrity || !integrity.startsWith("sha256-")) {
      return true;
    }
    const digest = new Uint8Array(await crypto.subtle.digest("SHA-256", buffer));
    let binary = "";
    for (const byte of digest) {
      binary += String.fromCharCode(byte);
    }
    return "sha256-" + btoa(binary) === integrity;
  }

  // The interpreter (pyodide.asm.wasm) is fetched as the browser fetches it, so that its
  // HTTP cache keeps, beside the file, the machine code it compiled from it, which the next
  // visit reuses (seconds on a small computer). A copy goes to Cache Storage for a visit
  // without network.
  async function interpreter(input, init, cache, key) {
    let response = null;
    try {
      response = await realFetch(input, init);
    } catch (error) {
      response = null;                                  // offline: the kept copy
    }
    if (response && response.ok) {
      if (cache && !(await cache.match(key))) {
        cache.put(key, response.clone()).catch(function () { /* no room */ });
      }
    } else {
      response = (cache && await cache.match(key)) || response;
    }
    if (!response) {
      throw new Error("the Python interpreter cannot be loaded: no network, and this browser " +
                      "has not kept it from an earlier visit");
    }
    const length = Number(response && response.headers.get("Content-Length")) || 0;
    progress.loaded += length;
    report(false);
    return response;
  }

  function cachingFetch(cache, base) {
    return async function (input, init) {
      const url = new URL(input instanceof Request ? input.url : String(input), self.location.href);
      if (!url.href.startsWith(base) || (init && init.method && init.method !== "GET")) {
        return realFetch(input, init);
      }
      const key = url.origin + url.pathname;
      if (url.pathname.endsWith(".wasm")) {
        return interpreter(input, init, cache, key);
      }
      const hit = cache ? await cache.match(key) : undefined;
      if (hit) {
        // the cached response itself (not a copy), so that the browser can reuse what it
        // compiled from it (the interpreter's WebAssembly) on an earlier visit
        const integrity = init && init.integrity;
        const length = Number(hit.headers.get("Content-Length"));
        const size = integrity || !length ? (await hit.clone().arrayBuffer()) : length;
        const ok = !integrity || await intact(size, integrity);
        if (ok) {
          const bytes = typeof size === "number" ? size : size.byteLength;
          progress.loaded += bytes;
          progress.cached += bytes;
          report(false);
          return hit;
        }
      }
      const response = await realFetch(input, init);   // checks the integrity it is given
      if (!response.ok) {
        return response;
      }
      const fresh = await counted(response);
      progress.fetched += fresh.byteLength;
      const headers = new Headers(response.headers);
      headers.set("Content-Length", String(fresh.byteLength));   // the bytes kept, decoded
      headers.delete("Content-Encoding");
      if (cache) {
        cache.put(key, new Response(fresh.slice(0), { status: 200, headers: headers }))
          .catch(function () { /* a full disk only means no cache */ });
      }
      return new Response(fresh, { status: 200, headers: headers });
    };
  }

  // --- what to load and import ----------------------------------------------------------

  function plan(manifest, notebook, requested) {
    const chapter = (notebook && manifest.notebooks[notebook]) || manifest.default;
    const skip = new Set(manifest.kernel.skip);
    const packages = [];
    for (const name of [...requested, ...chapter.packages]) {
      if (!skip.has(name) && !packages.includes(name)) {
        packages.push(name);
      }
    }
    return { packages: packages, modules: chapter.modules, bytes: chapter.bytes };
  }

  // Whether a cell's code imports ``module`` (a dotted name: "dqlab.viz"), in any form:
  // "import dqlab.viz", "from dqlab.viz import x", "from dqlab import (models, viz)".
  function importsModule(code, module) {
    const dot = module.lastIndexOf(".");
    const parent = module.slice(0, dot).replace(/\./g, "\\.");
    const child = module.slice(dot + 1);
    const direct = new RegExp("^\\s*(import\\s[^\\n]*\\b" + parent + "\\." + child +
                              "\\b|from\\s+" + parent + "\\." + child + "\\b)", "m");
    if (direct.test(code)) {
      return true;
    }
    const from = new RegExp("^\\s*from\\s+" + parent + "\\s+import\\s+(\\([^)]*\\)|[^\\n]*)",
                            "gm");
    for (const match of code.matchAll(from)) {
      if (new RegExp("\\b" + child + "\\b").test(match[1])) {
        return true;
      }
    }
    return false;
  }

  // The kernel loads the packages a cell imports before running it; a module that needs
  // more than its package (manifest.on_import) gets those too.
  function loadAlsoOnImport(pyodide, onImport) {
    const loadFromImports = pyodide.loadPackagesFromImports;
    pyodide.loadPackagesFromImports = async function (code, options) {
      const result = await loadFromImports.call(pyodide, code, options);
      const more = [];
      for (const [module, packages] of Object.entries(onImport)) {
        if (importsModule(code, module)) {
          more.push(...packages);
        }
      }
      if (more.length) {
        await pyodide.loadPackage(more, options);
      }
      return result;
    };
  }

  // matplotlib's font list, which it builds on its first import (seconds): kept in the cache
  // with the downloads and written back before the next start imports matplotlib.
  const MPL_CACHE = "/home/pyodide/.cache/matplotlib";

  async function restoreFontList(pyodide, cache, base) {
    if (!cache) {
      return [];
    }
    const restored = [];
    for (const request of await cache.keys()) {
      const url = new URL(request.url);
      const prefix = new URL(base).pathname + "matplotlib-cache/";
      if (url.pathname.startsWith(prefix)) {
        const name = url.pathname.slice(prefix.length);
        const bytes = new Uint8Array(await (await cache.match(request)).arrayBuffer());
        pyodide.FS.mkdirTree(MPL_CACHE);
        pyodide.FS.writeFile(MPL_CACHE + "/" + name, bytes);
        restored.push(name);
      }
    }
    return restored;
  }

  async function keepFontList(pyodide, cache, base, restored) {
    if (!cache || !pyodide.FS.analyzePath(MPL_CACHE).exists) {
      return;
    }
    for (const name of pyodide.FS.readdir(MPL_CACHE)) {
      if (name.endsWith(".json") && !restored.includes(name)) {
        const bytes = pyodide.FS.readFile(MPL_CACHE + "/" + name);
        await cache.put(new URL("matplotlib-cache/" + name, base).href,
                        new Response(bytes, { headers: { "Content-Type": "application/json" } }))
          .catch(function () { /* no room: built again next time */ });
      }
    }
  }

  const IMPORTS = `
import importlib, os
# the backend the kernel sets when it starts, set before matplotlib is imported
os.environ.setdefault("MPLBACKEND", "module://matplotlib_inline.backend_inline")
os.environ.setdefault("MPLCONFIGDIR", "${MPL_CACHE}")
import time
failed, seconds = [], []
for name in ["pyodide_kernel", *MODULES]:
    start = time.perf_counter()
    try:
        importlib.import_module(name)
    except Exception as error:
        failed.append(f"{name}: {type(error).__name__}: {error}"[:300])
    seconds.append(f"{name} {time.perf_counter() - start:.2f} s")
failed, seconds
`;

  // for the site's tests (tests/test_lite.py), which run these two in Node
  self.dqlabLite = { importsModule: importsModule, plan: plan };

  self.loadPyodide = async function (options) {
    try {
      return await start(options);
    } catch (error) {
      tell({ event: "error", message: String(error && error.message || error).slice(0, 500) });
      throw error;
    }
  };

  async function start(options) {
    const base = options.indexURL;
    importScripts(base + "pyodide.js");                 // Pyodide's own loadPyodide
    const load = self.loadPyodide;
    const started = Date.now();
    let manifest = null;
    try {
      const response = await realFetch(base + "dqlab-lite.json", { cache: "no-cache" });
      manifest = response.ok ? await response.json() : null;
    } catch (error) {
      manifest = null;
    }
    if (!manifest) {                                    // a site without it: Pyodide as is
      return load(options);
    }
    const cache = await openCache(CACHE_PREFIX + manifest.build);
    const warm = cache ? (await cache.keys()).length > 0 : false;
    self.fetch = cachingFetch(cache, base);
    // the interpreter loads while the page says which chapter this is
    const asked = askNotebook(15000);
    progress.total = manifest.default.bytes;
    tell({ event: "phase", phase: "runtime", total: progress.total, warm: warm });
    const runtime = load(Object.assign({}, options, { packages: [] }));
    const notebook = await asked;
    const todo = plan(manifest, notebook, options.packages || []);
    progress.total = todo.bytes;
    tell({ event: "phase", phase: "runtime", total: todo.bytes, warm: warm,
           notebook: notebook });
    const pyodide = await runtime;
    const interpreter = (Date.now() - started) / 1000;
    await pyodide.loadPackage(todo.packages);
    report(true);
    console.log("dqlab: Python started in " + interpreter + " s, its packages loaded in " +
                ((Date.now() - started) / 1000) + " s (" + progress.fetched + " bytes downloaded, " +
                progress.cached + " from the cache)");
    loadAlsoOnImport(pyodide, manifest.on_import || {});
    tell({ event: "phase", phase: "imports", modules: todo.modules,
           seconds: (Date.now() - started) / 1000 });
    const restored = await restoreFontList(pyodide, cache, base);
    const namespace = pyodide.toPy({});               // no name left in the reader's
    const failed = await pyodide.runPythonAsync(      // namespace; the modules stay imported
      IMPORTS.replace("MODULES", JSON.stringify(todo.modules)), { globals: namespace });
    const [problems, seconds] = failed.toJs();
    failed.destroy();
    namespace.destroy();
    console.log("dqlab: imported in " + seconds.join(", "));
    await keepFontList(pyodide, cache, base, restored);
    tell({ event: "phase", phase: "imported", problems: problems, imports: seconds,
           seconds: (Date.now() - started) / 1000, loaded: progress.loaded,
           fetched: progress.fetched, cached: progress.cached });
    return pyodide;
  }
})();
