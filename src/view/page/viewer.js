// sesi view: the page's UI and rendering (docs/view.md). Plain ES2020, no modules; it runs after geometry.js
// (global SesiGeometry), which owns every formula: projections, isometries, polygon lines, colours, base64.
// The page reads #sesi-meta and #sesi-frames (or fetches frames/<k> in stream mode), draws with WebGL2
// (WebGL1, then canvas 2D as fallbacks) and writes its state into #sesi-state after every draw (for tests).
(function () {
  'use strict';

  const $ = (id) => document.getElementById(id);
  const state = {
    ready: false, frame: 0, frames: 0, t: 0, space: '', projection: '', projections: [], renderer: '',
    canvas: { left: 0, top: 0, width: 0, height: 0 }, origin: [0, 0], scale: 1, camera: null, isometry: [],
    screen: [], colours: [], point_px: 0, messages: [], errors: [], resources: [], first_draw_ms: null, note: ''
  };
  const banners = [];  // {text, note}

  function writeState() {
    try {
      state.messages = banners.map((b) => b.text);
      const ld = $('loading');
      if (ld && !ld.hidden && ld.textContent) state.messages.push(ld.textContent);
      state.resources = performance.getEntriesByType('resource').map((e) => e.name);
      const el = $('sesi-state');
      if (el) el.textContent = JSON.stringify(state);
    } catch (e) { /* the state element is for tests; never fail a draw on it */ }
  }

  function showBanners() {
    const box = $('banners');
    if (!box) return;
    box.textContent = '';
    for (const b of banners) {
      const d = document.createElement('div');
      if (b.note) d.className = 'note';
      d.textContent = b.text;
      box.appendChild(d);
    }
  }

  function banner(text, note) {
    if (banners.some((b) => b.text === text)) return;
    banners.push({ text: text, note: !!note });
    showBanners();
    writeState();
    // A banner moves the canvas down: redraw so that the state's screen positions follow it.
    if (state.ready) scheduleDraw();
  }

  function recordError(text) {
    text = String(text);
    state.errors.push(text);
    banner('Error: ' + text);
  }

  // Errors anywhere on the page are shown and recorded (never a blank page).
  window.addEventListener('error', (ev) => {
    recordError(ev.message || (ev.error && ev.error.message) || 'unknown error');
  });
  window.addEventListener('unhandledrejection', (ev) => {
    const r = ev.reason;
    recordError((r && r.message) || String(r));
  });
  const consoleError = console.error.bind(console);
  console.error = function () {
    state.errors.push(Array.prototype.map.call(arguments, String).join(' '));
    writeState();
    consoleError.apply(null, arguments);
  };

  // URL parameters, from the query and the hash (the hash wins).
  function readParams() {
    const p = {};
    const add = (s) => {
      if (!s) return;
      for (const [k, v] of new URLSearchParams(s)) p[k] = v;
    };
    add(location.search.replace(/^\?/, ''));
    add(location.hash.replace(/^#/, ''));
    return p;
  }

  function num(v, fallback) {
    const x = Number(v);
    return v !== undefined && v !== '' && Number.isFinite(x) ? x : fallback;
  }

  function fmt(x) {
    if (!Number.isFinite(x)) return String(x);
    const a = Math.abs(x);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential(3);
    return String(Number(x.toPrecision(5)));
  }

  // ---------------------------------------------------------------- meta and frames
  // Bad run data: a banner naming it (not a page error).
  class DataError extends Error {}
  const G = window.SesiGeometry;
  let meta = null;
  let N = 0, A = 0, F = 0;
  let framesText = '';
  let lineStart = null;  // packed frames: offsets of each line in framesText
  const cache = new Map();  // k -> {x, speed, jumps, bytes}; insertion order = recency
  let cacheBytes = 0;
  const CACHE_LIMIT = 256 * 1024 * 1024;  // decoded frames kept, bytes (trails need several at once)
  const pending = new Map();  // stream mode: k -> Promise
  const failed = new Set();
  let speedMax = 0, energyMax = 0;  // colour ranges over the frames decoded so far

  function readMeta() {
    const el = $('sesi-meta');
    const text = el ? el.textContent.trim() : '';
    if (!text || text === '/*SESI_META*/') throw new DataError('The page has no run data (#sesi-meta is missing or empty).');
    let m;
    try { m = JSON.parse(text); } catch (e) { throw new DataError('The run data (#sesi-meta) is not valid JSON: ' + e.message); }
    const bad = (what) => { throw new DataError('The run data (#sesi-meta) is invalid: ' + what + '.'); };
    if (!m || typeof m !== 'object') bad('not an object');
    if (m.format !== 'sesi-view 1') bad('format is ' + JSON.stringify(m.format) + ', expected "sesi-view 1"');
    const s = m.space;
    if (!s || ['sphere', 'hyperbolic', 'euclidean'].indexOf(s.kind) < 0) bad('space.kind is missing or unknown');
    if (!(Number.isInteger(s.dim) && s.dim >= 1)) bad('space.dim is not a positive integer');
    const amb = s.kind === 'euclidean' ? s.dim : s.dim + 1;
    if (m.ambient !== amb) bad('ambient is ' + m.ambient + ', expected ' + amb);
    if (!(Number.isInteger(m.bodies) && m.bodies >= 0)) bad('bodies is not a count');
    const f = m.frames;
    if (!f || !Number.isInteger(f.count) || f.count < 0) bad('frames.count is missing');
    if (!Array.isArray(f.t) || f.t.length !== f.count) bad('frames.t does not have frames.count times');
    if (f.encoding !== 'f32' && f.encoding !== 'f64') bad('frames.encoding is ' + JSON.stringify(f.encoding));
    return m;
  }

  function indexFrames() {
    const el = $('sesi-frames');
    framesText = el ? el.textContent : '';
    if (framesText === '/*SESI_FRAMES*/') framesText = '';
    // The page keeps the text in this string only: the DOM copy goes (less memory; a dumped DOM stays small).
    if (el && framesText) el.textContent = '';
    lineStart = [];
    let i = 0;
    while (i < framesText.length && (framesText[i] === '\n' || framesText[i] === '\r' || framesText[i] === ' ')) i++;
    if (i >= framesText.length) return;
    lineStart.push(i);
    for (;;) {
      const j = framesText.indexOf('\n', i);
      if (j < 0 || j + 1 >= framesText.length) break;
      i = j + 1;
      if (framesText.charCodeAt(i) <= 32) continue;  // a blank line (only at the end)
      lineStart.push(i);
    }
  }

  function frameLine(k) {
    const a = lineStart[k];
    let b = framesText.indexOf('\n', a);
    if (b < 0) b = framesText.length;
    return framesText.substring(a, b).trim();
  }

  function decodeLine(k, line) {
    const parts = line.split(',');
    const f = meta.frames;
    const expected = 1 + (f.speed ? 1 : 0) + (f.jumps ? 1 : 0);
    if (parts.length !== expected) {
      throw new DataError('frame ' + k + ' has ' + parts.length + ' fields, expected ' + expected);
    }
    const bytes = f.encoding === 'f64' ? 8 : 4;
    let raw = G.decodeBase64(parts[0]);
    if (raw.byteOffset % bytes !== 0) raw = raw.slice();  // typed-array views need aligned offsets
    if (raw.length !== N * A * bytes) {
      throw new DataError('frame ' + k + ' positions have ' + raw.length + ' bytes, expected ' + N * A * bytes);
    }
    // Little-endian data, read in place (every browser this runs in is little-endian).
    const x = bytes === 8 ? new Float64Array(raw.buffer, raw.byteOffset, N * A)
                          : new Float32Array(raw.buffer, raw.byteOffset, N * A);
    let speed = null, jumps = null, p = 1;
    if (f.speed) {
      let r = G.decodeBase64(parts[p++]);
      if (r.byteOffset % 4 !== 0) r = r.slice();
      if (r.length !== 4 * N) throw new DataError('frame ' + k + ' speeds have ' + r.length + ' bytes, expected ' + 4 * N);
      speed = new Float32Array(r.buffer, r.byteOffset, N);
      const m = meta.masses;
      for (let b = 0; b < N; b++) {
        const s = speed[b];
        if (s > speedMax) speedMax = s;
        const e = 0.5 * (m.length === N ? m[b] : 1) * s * s;
        if (e > energyMax) energyMax = e;
      }
    }
    if (f.jumps) {
      jumps = G.decodeBase64(parts[p++]);
      if (jumps.length !== N) throw new DataError('frame ' + k + ' jump flags have ' + jumps.length + ' bytes, expected ' + N);
    }
    return { x: x, speed: speed, jumps: jumps, bytes: raw.length + (speed ? 4 * N : 0) + (jumps ? N : 0) };
  }

  function remember(k, fr) {
    cache.set(k, fr);
    cacheBytes += fr.bytes;
    for (const [key, old] of cache) {
      if (cacheBytes <= CACHE_LIMIT || cache.size <= 2) break;
      if (key === k || key === current) continue;
      cache.delete(key);
      cacheBytes -= old.bytes;
    }
  }

  // The decoded frame k, or null (stream mode: the fetch is started and a redraw follows it).
  function getFrame(k) {
    const hit = cache.get(k);
    if (hit) {
      cache.delete(k);
      cache.set(k, hit);
      return hit;
    }
    if (meta.frames.stream) {
      fetchFrame(k);
      return null;
    }
    if (k >= lineStart.length) throw new DataError('frame ' + k + ' is missing from the page (it holds ' + lineStart.length + ' frame lines)');
    const fr = decodeLine(k, frameLine(k));
    remember(k, fr);
    return fr;
  }

  function fetchFrame(k) {
    if (pending.has(k) || failed.has(k)) return;
    const p = fetch('frames/' + k).then((r) => {
      if (!r.ok) throw new Error('HTTP status ' + r.status + (r.statusText ? ' ' + r.statusText : ''));
      return r.text();
    }).then((text) => {
      pending.delete(k);
      remember(k, decodeLine(k, text.trim()));
      scheduleDraw();
    }).catch((e) => {
      pending.delete(k);
      failed.add(k);
      banner('Could not load frame ' + k + ' (frames/' + k + '): ' + e.message);
      scheduleDraw();
    });
    pending.set(k, p);
  }

  // ---------------------------------------------------------------- view
  let view = null, iso = null, projName = '', viewFitted = false;
  let camera = null;  // Float64Array(9), row-major, 3-D views only
  let zoom = 1;
  const params = readParams();
  let current = 0;
  let colourMode = 'body', trail = 0, sizeFactor = 1, tilesOn = false, playing = false;
  let bodyCols = null;  // Float32Array(N*3), 0-1

  function defaultCamera() {
    // Base: plane (x, y, z) -> screen (x right, z up, -y towards the viewer), turned by 0.5 rad about the
    // vertical and tilted by 0.35 rad about the screen's x axis so that the top (the north pole, the
    // hyperboloid's bowl, a box's lid) leans towards the viewer.
    const a = 0.35, c = Math.cos(a), s = Math.sin(a), y = 0.5, cy = Math.cos(y), sy = Math.sin(y);
    const base = [1, 0, 0, 0, 0, 1, 0, -1, 0];
    const yaw = [cy, 0, sy, 0, 1, 0, -sy, 0, cy];
    const tilt = [1, 0, 0, 0, c, -s, 0, s, c];
    return mul3(tilt, mul3(yaw, base));
  }

  function mul3(a, b) {
    const r = new Float64Array(9);
    for (let i = 0; i < 3; i++) {
      for (let j = 0; j < 3; j++) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    }
    return r;
  }

  function setView(name) {
    const names = G.projections(meta.space);
    if (names.indexOf(name) < 0) name = names[0];
    projName = name;
    view = G.makeView(meta.space, name, axes);
    iso = view.identity();
    viewFitted = false;
    camera = view.dims === 3 ? defaultCamera() : null;
    zoom = 1;
    state.projection = name;
    state.projections = names;
    state.note = view.note || '';
    const sel = $('projection');
    if (sel) sel.value = name;
    $('recentre').hidden = view.dims !== 2 || meta.space.kind === 'euclidean' && !meta.space.box;
    if (pole) setPole(pole);  // a new projection keeps the chosen pole
  }

  // n > 3: the three coordinates shown (0-based; null: the first three), from axes=i,j,k (1-based)
  // or the "axes" field.
  let axes = null;
  function parseAxes(text) {
    const n = meta.space.dim;
    const parts = String(text).split(/[ ,]+/).filter((w) => w !== '').map(Number);
    if (parts.length !== 3 || !parts.every((k) => Number.isInteger(k) && k >= 1 && k <= n) || new Set(parts).size !== 3) {
      return null;
    }
    return parts.map((k) => k - 1);
  }
  function setAxes(text) {
    const parsed = parseAxes(text);
    if (!parsed) return false;
    axes = parsed;
    const keep = iso;
    setView(projName);
    iso = keep;  // the same isometry (pole, centre), other coordinates shown
    const field = $('axes');
    if (field) field.value = axes.map((k) => k + 1).join(',');
    return true;
  }

  // The pole of S^n's views (the point drawn at the centre; stereographic projection is from its
  // antipode): an axis point +-R e_k of the embedding, as "+k" / "-k" (1-based); the north pole
  // +R e_{n+1} is the default (pole = ''). A body picked as the centre replaces it (pole = '').
  let pole = '';
  function poleSpecs() {
    if (!meta || meta.space.kind !== 'sphere' || A < 2) return [];
    const out = [];
    for (let k = A; k >= 1; k--) out.push('+' + k, '-' + k);
    return out;
  }
  function poleLabel(spec) {
    const north = spec === '+' + A ? ' (north)' : spec === '-' + A ? ' (south)' : '';
    return (spec[0] === '+' ? '+' : '\u2212') + 'x' + spec.slice(1) + north;
  }
  function setPole(spec) {
    if (poleSpecs().indexOf(spec) < 0) return false;
    const k = Number(spec.slice(1)) - 1;
    const x = new Float64Array(A);
    x[k] = (spec[0] === '-' ? -1 : 1) * meta.space.radius;
    iso = spec === '+' + A ? view.identity() : view.centreOn(x);
    pole = spec === '+' + A ? '' : spec;
    // The globe: the camera faces the north pole, where the chosen pole now is.
    if (projName === 'sphere' && camera && pole) camera = Float64Array.of(1, 0, 0, 0, 1, 0, 0, 0, 1);
    const ps = $('pole');
    if (ps) ps.value = spec;
    return true;
  }

  // ---------------------------------------------------------------- rendering back ends
  let canvas = $('canvas');
  let gl = null, ctx2d = null, prog = null, vbo = null, loc = null;
  let dpr = 1, cssW = 0, cssH = 0;

  const VS = 'attribute vec2 a_pos; attribute float a_size; attribute vec4 a_col;\n' +
    'uniform vec2 u_view; uniform float u_dpr; varying vec4 v_col;\n' +
    'void main() { gl_Position = vec4(a_pos.x / u_view.x * 2.0 - 1.0, 1.0 - a_pos.y / u_view.y * 2.0, 0.0, 1.0);\n' +
    '  gl_PointSize = a_size * u_dpr; v_col = a_col; }\n';
  // Round points: fragments outside the inscribed circle are discarded; a darker rim keeps touching bodies apart.
  const FS = 'precision mediump float; varying vec4 v_col; uniform float u_round;\n' +
    'void main() { float shade = 1.0;\n' +
    '  if (u_round > 0.5) { vec2 d = gl_PointCoord - vec2(0.5); float r2 = dot(d, d); if (r2 > 0.25) discard;\n' +
    '    shade = r2 > 0.16 ? 0.7 : 1.0; }\n' +
    '  gl_FragColor = vec4(v_col.rgb * shade, v_col.a); }\n';

  function initProgram() {
    const sh = (type, src) => {
      const x = gl.createShader(type);
      gl.shaderSource(x, src);
      gl.compileShader(x);
      if (!gl.getShaderParameter(x, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(x));
      return x;
    };
    prog = gl.createProgram();
    gl.attachShader(prog, sh(gl.VERTEX_SHADER, VS));
    gl.attachShader(prog, sh(gl.FRAGMENT_SHADER, FS));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error('shader link: ' + gl.getProgramInfoLog(prog));
    loc = {
      pos: gl.getAttribLocation(prog, 'a_pos'), size: gl.getAttribLocation(prog, 'a_size'),
      col: gl.getAttribLocation(prog, 'a_col'), view: gl.getUniformLocation(prog, 'u_view'),
      dpr: gl.getUniformLocation(prog, 'u_dpr'), round: gl.getUniformLocation(prog, 'u_round')
    };
    vbo = gl.createBuffer();
  }

  function initRenderer() {
    const opts = { antialias: true, preserveDrawingBuffer: true, alpha: false };
    const want = params.renderer;
    if (want !== 'canvas2d') {
      if (want !== 'webgl') gl = canvas.getContext('webgl2', opts);
      if (gl) state.renderer = 'webgl2';
      else {
        gl = canvas.getContext('webgl', opts) || canvas.getContext('experimental-webgl', opts);
        if (gl) state.renderer = 'webgl';
      }
    }
    if (gl) {
      try {
        initProgram();
        canvas.addEventListener('webglcontextlost', (ev) => {
          ev.preventDefault();
          banner('The browser dropped the WebGL context (GPU reset or too many pages): reload the page.');
        });
        return;
      } catch (e) {
        // A WebGL that cannot build the shaders: a fresh canvas (a canvas keeps its first context) drawn in 2D.
        banner('WebGL failed (' + (e && e.message ? e.message : e) + '): drawing with canvas 2D.', true);
        const fresh = canvas.cloneNode(false);
        canvas.parentNode.replaceChild(fresh, canvas);
        canvas = fresh;
        gl = null;
        ctx2d = canvas.getContext('2d');
        state.renderer = 'canvas2d';
        return;
      }
    }
    ctx2d = canvas.getContext('2d');
    state.renderer = 'canvas2d';
    banner(want === 'canvas2d' ? 'Drawing with canvas 2D (renderer=canvas2d).'
                               : 'WebGL is not available in this browser: drawing with canvas 2D (slower).', true);
  }

  function layout() {
    dpr = window.devicePixelRatio || 1;
    const pw = num(params.width, 0), ph = num(params.height, 0);
    if (pw > 0 && ph > 0) {
      cssW = Math.round(pw);
      cssH = Math.round(ph);
    } else {
      cssW = Math.max(200, Math.floor(document.documentElement.clientWidth - 22));
      canvas.style.height = '10px';
      // The height of everything else on the page (the body's own height, not the viewport's).
      const rest = Math.ceil(document.body.getBoundingClientRect().height) - 12;
      cssH = Math.max(280, Math.floor(window.innerHeight - rest - 4));
      if (pw > 0) cssW = Math.round(pw);
      if (ph > 0) cssH = Math.round(ph);
    }
    canvas.style.width = cssW + 'px';
    canvas.style.height = cssH + 'px';
    if (!(ph > 0)) {
      // Whatever still overflows the window (controls that wrapped at this width, the diagnostics)
      // comes off the canvas, so that no scroll bar appears (a vertical one would also steal width).
      const over = document.documentElement.scrollHeight - window.innerHeight;
      if (over > 0) {
        cssH = Math.max(280, cssH - over);
        canvas.style.height = cssH + 'px';
      }
    }
    canvas.width = Math.round(cssW * dpr);
    canvas.height = Math.round(cssH * dpr);
  }

  // Vertex batches, built on the CPU each draw: points [sx, sy, size, r, g, b, a], lines [sx, sy, 0, r, g, b, a].
  class Batch {
    constructor() { this.a = new Float32Array(7 * 1024); this.n = 0; }
    reset() { this.n = 0; }
    grow(m) {
      if (7 * (this.n + m) <= this.a.length) return;
      let len = this.a.length;
      while (len < 7 * (this.n + m)) len *= 2;
      const b = new Float32Array(len);
      b.set(this.a.subarray(0, 7 * this.n));
      this.a = b;
    }
    push(x, y, s, r, g, b, al) {
      const i = 7 * this.n++;
      const a = this.a;
      a[i] = x; a[i + 1] = y; a[i + 2] = s; a[i + 3] = r; a[i + 4] = g; a[i + 5] = b; a[i + 6] = al;
    }
  }
  const lines = new Batch(), points = new Batch();

  function flush() {
    if (gl) {
      gl.viewport(0, 0, canvas.width, canvas.height);
      gl.clearColor(0.043, 0.051, 0.063, 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.enable(gl.BLEND);
      gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
      gl.useProgram(prog);
      gl.uniform2f(loc.view, cssW, cssH);
      gl.uniform1f(loc.dpr, dpr);
      gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
      const draw = (batch, mode, round) => {
        if (!batch.n) return;
        gl.bufferData(gl.ARRAY_BUFFER, batch.a.subarray(0, 7 * batch.n), gl.DYNAMIC_DRAW);
        gl.enableVertexAttribArray(loc.pos);
        gl.vertexAttribPointer(loc.pos, 2, gl.FLOAT, false, 28, 0);
        if (loc.size >= 0) {
          gl.enableVertexAttribArray(loc.size);
          gl.vertexAttribPointer(loc.size, 1, gl.FLOAT, false, 28, 8);
        }
        gl.enableVertexAttribArray(loc.col);
        gl.vertexAttribPointer(loc.col, 4, gl.FLOAT, false, 28, 12);
        gl.uniform1f(loc.round, round ? 1 : 0);
        gl.drawArrays(mode, 0, batch.n);
      };
      draw(lines, gl.LINES, false);
      draw(points, gl.POINTS, true);
      return;
    }
    const c = ctx2d;
    c.setTransform(dpr, 0, 0, dpr, 0, 0);
    c.fillStyle = '#0b0d10';
    c.fillRect(0, 0, cssW, cssH);
    const rgba = (a, i) => 'rgba(' + Math.round(255 * a[i + 3]) + ',' + Math.round(255 * a[i + 4]) + ',' +
      Math.round(255 * a[i + 5]) + ',' + a[i + 6].toFixed(3) + ')';
    c.lineWidth = 1;
    for (let v = 0; v + 1 < lines.n; v += 2) {
      const i = 7 * v;
      c.strokeStyle = rgba(lines.a, i);
      c.beginPath();
      c.moveTo(lines.a[i], lines.a[i + 1]);
      c.lineTo(lines.a[i + 7], lines.a[i + 8]);
      c.stroke();
    }
    for (let v = 0; v < points.n; v++) {
      const i = 7 * v, a = points.a;
      c.fillStyle = rgba(a, i);
      c.beginPath();
      c.arc(a[i], a[i + 1], a[i + 2] / 2, 0, 2 * Math.PI);
      c.fill();
    }
  }

  // ---------------------------------------------------------------- projection to the screen
  let ox = 0, oy = 0, sc = 1, ext = 1;
  let proj = null, vis = null;  // projected plane points of the current frame (identity tile)
  let scr = null, scrVis = null;  // screen px (canvas-relative) of the current frame's bodies

  function setScreenTransform() {
    ext = view.extent();
    const half = Math.min(cssW, cssH) / 2;
    // 3-D: a box's corners reach sqrt(3) half-widths from the centre whichever way the camera turns; the
    // hyperboloid's bowl spans heights 0 to about extent, so its middle height is put at the canvas's middle.
    const bowl = projName === 'hyperboloid' && !!camera;
    const reach = camera ? (meta.space.kind === 'euclidean' ? Math.sqrt(3) : bowl ? 1.0 : 1.1) : 1;
    sc = half * 0.92 / (ext * reach) * zoom;
    // The view's centre point (the half-plane's i, else the plane's origin) is drawn at the canvas's middle.
    const c = bowl ? [0, 0, 0.5 * ext] : view.centre || [0, 0, 0];
    let cx = c[0], cy = c[1];
    if (camera) {
      cx = camera[0] * c[0] + camera[1] * c[1] + camera[2] * c[2];
      cy = camera[3] * c[0] + camera[4] * c[1] + camera[5] * c[2];
    }
    ox = cssW / 2 - sc * cx;
    oy = cssH / 2 + sc * cy;
  }

  // Plane point -> screen [x, y, depth] (depth > 0: towards the viewer).
  function toScreen(px, py, pz, out) {
    if (camera) {
      const m = camera;
      const cx = m[0] * px + m[1] * py + m[2] * pz, cy = m[3] * px + m[4] * py + m[5] * pz;
      out[0] = ox + sc * cx;
      out[1] = oy - sc * cy;
      out[2] = m[6] * px + m[7] * py + m[8] * pz;
    } else {
      out[0] = ox + sc * px;
      out[1] = oy - sc * py;
      out[2] = 0;
    }
    return out;
  }

  function pushPolylines(polys, r, g, b, a) {
    const s0 = [0, 0, 0], s1 = [0, 0, 0];
    for (const pl of polys) {
      if (!pl || pl.length < 6) continue;
      lines.grow(2 * (pl.length / 3));
      for (let i = 3; i + 2 < pl.length; i += 3) {
        const x0 = pl[i - 3], y0 = pl[i - 2], z0 = pl[i - 1], x1 = pl[i], y1 = pl[i + 1], z1 = pl[i + 2];
        if (!(Number.isFinite(x0) && Number.isFinite(y0) && Number.isFinite(x1) && Number.isFinite(y1))) continue;
        toScreen(x0, y0, z0 || 0, s0);
        toScreen(x1, y1, z1 || 0, s1);
        // Dim the back half of 3-D outlines (the globe's far side).
        const al = camera && s0[2] + s1[2] < 0 && projName === 'sphere' ? a * 0.35 : a;
        lines.push(s0[0], s0[1], 0, r, g, b, al);
        lines.push(s1[0], s1[1], 0, r, g, b, al);
      }
    }
  }

  function bodyColour(fr, b, out) {
    if (colourMode === 'body' || !fr || !fr.speed) {
      out[0] = bodyCols[3 * b]; out[1] = bodyCols[3 * b + 1]; out[2] = bodyCols[3 * b + 2];
      return out;
    }
    let s;
    if (colourMode === 'speed') s = speedMax > 0 ? fr.speed[b] / speedMax : 0;
    else {
      const m = meta.masses.length === N ? meta.masses[b] : 1;
      s = energyMax > 0 ? 0.5 * m * fr.speed[b] * fr.speed[b] / energyMax : 0;
    }
    const c = G.colourmap('viridis', Math.min(1, Math.max(0, s)));
    out[0] = c[0] / 255; out[1] = c[1] / 255; out[2] = c[2] / 255;
    return out;
  }

  function pointSize(px, py, pz) {
    if (!(meta.body_radius > 0)) return 4 * sizeFactor > 64 ? 64 : Math.max(1.5, 4 * sizeFactor);
    const ls = view.localScale([px, py, pz]);
    const d = 2 * meta.body_radius * ls * sc * sizeFactor;
    return Number.isFinite(d) ? Math.min(64, Math.max(1.5, d)) : 1.5;
  }

  // ---------------------------------------------------------------- drawing
  let drawQueued = false;
  function scheduleDraw() {
    if (drawQueued) return;
    drawQueued = true;
    requestAnimationFrame(() => { drawQueued = false; draw(); });
  }

  function drawSafe() {
    try { draw(); } catch (e) { recordError(e && e.message ? e.message : String(e)); }
  }

  function draw() {
    if (!meta || !view) return;
    let fr = null;
    $('loading').hidden = true;
    if (F > 0) {
      try {
        fr = failed.has(current) ? null : getFrame(current);
      } catch (e) {
        if (!(e instanceof DataError)) throw e;
        failed.add(current);
        banner('Cannot show frame ' + current + ': ' + e.message);
      }
      if (!fr) {
        const ld = $('loading');
        ld.hidden = false;
        ld.textContent = failed.has(current) ? 'frame ' + current + ' could not be loaded' : 'loading frame ' + current + ' ...';
      }
    }
    // Unbounded views (hyperboloid, flat without a box) fit their extent to the first frame they show.
    if (fr && !viewFitted) {
      if (view.fit) view.fit(fr.x, N, iso);
      viewFitted = true;
    }
    setScreenTransform();
    lines.reset();
    points.reset();
    const outlineCol = [0.55, 0.6, 0.68];
    pushPolylines(view.outlines(iso) || [], outlineCol[0], outlineCol[1], outlineCol[2], 0.8);
    if (meta.polygon && view.polygonLines && meta.space.kind === 'hyperbolic' && meta.space.dim === 2) {
      if (tilesOn) pushPolylines(view.polygonLines(meta.polygon, iso, true) || [], 0.45, 0.5, 0.7, 0.45);
      pushPolylines(view.polygonLines(meta.polygon, iso, false) || [], 0.95, 0.8, 0.4, 0.95);
    }
    if (fr) {
      if (!proj || proj.length !== 3 * N) {
        proj = new Float32Array(3 * N);
        vis = new Uint8Array(N);
        scr = new Float32Array(3 * N);
        scrVis = new Uint8Array(N);
      }
      view.project(fr.x, N, iso, proj, vis);
      drawTrails(fr);
      drawPoints(fr);
    }
    flush();
    updateText(fr);
    if (fr) {
      if (!state.ready) {
        state.ready = true;
        state.first_draw_ms = performance.now();
      }
    }
    fillState(fr);
    writeState();
  }

  function drawTrails(fr) {
    if (trail <= 0 || current === 0) return;
    const k0 = Math.max(0, current - trail);
    // Project the frames k0..current (all decoded or fetched; missing ones break the trail).
    const P = [], V = [], J = [];
    for (let j = k0; j <= current; j++) {
      let f = null;
      try { f = j === current ? fr : failed.has(j) ? null : getFrame(j); } catch (e) {
        if (!(e instanceof DataError)) throw e;
        failed.add(j);
      }
      if (!f) { P.push(null); V.push(null); J.push(null); continue; }
      if (j === current) { P.push(proj); V.push(vis); J.push(f.jumps); continue; }
      const p = new Float32Array(3 * N), v = new Uint8Array(N);
      view.project(f.x, N, iso, p, v);
      P.push(p); V.push(v); J.push(f.jumps);
    }
    const globe = projName === 'sphere' && !!camera;
    const maxLen = ext / 2;  // segments longer than a quarter of the view's extent (2 ext) are wraps: broken
    const col = [0, 0, 0], s0 = [0, 0, 0], s1 = [0, 0, 0];
    const L = P.length;
    lines.grow(2 * N * (L - 1));
    for (let b = 0; b < N; b++) {
      bodyColour(fr, b, col);
      for (let i = 1; i < L; i++) {
        const p = P[i - 1], q = P[i];
        if (!p || !q || !V[i - 1][b] || !V[i][b] || (J[i] && J[i][b])) continue;
        const dx = q[3 * b] - p[3 * b], dy = q[3 * b + 1] - p[3 * b + 1], dz = q[3 * b + 2] - p[3 * b + 2];
        if (dx * dx + dy * dy + dz * dz > maxLen * maxLen) continue;
        toScreen(p[3 * b], p[3 * b + 1], p[3 * b + 2], s0);
        toScreen(q[3 * b], q[3 * b + 1], q[3 * b + 2], s1);
        let al = 0.15 + 0.6 * i / (L - 1);  // older segments fade
        if (globe && s0[2] + s1[2] < 0) al *= 0.4;  // the globe's far side, as its points
        lines.push(s0[0], s0[1], 0, col[0], col[1], col[2], al);
        lines.push(s1[0], s1[1], 0, col[0], col[1], col[2], al);
      }
    }
  }

  function drawPoints(fr) {
    const col = [0, 0, 0], s = [0, 0, 0];
    const tiles = tilesOn && meta.polygon && meta.polygon.tiles ? meta.polygon.tiles : null;
    // Images of the bodies in the neighbouring tiles (the identity tile, first, is drawn below).
    if (tiles && tiles.length > 1) {
      const p = new Float32Array(3 * N), v = new Uint8Array(N);
      for (let t = 1; t < tiles.length; t++) {
        const T = { m: Float64Array.from(tiles[t]), t: null };
        view.project(fr.x, N, view.compose(iso, T), p, v);
        points.grow(N);
        for (let b = 0; b < N; b++) {
          if (!v[b]) continue;
          toScreen(p[3 * b], p[3 * b + 1], p[3 * b + 2], s);
          if (s[0] < -64 || s[1] < -64 || s[0] > cssW + 64 || s[1] > cssH + 64) continue;
          bodyColour(fr, b, col);
          points.push(s[0], s[1], pointSize(p[3 * b], p[3 * b + 1], p[3 * b + 2]), col[0], col[1], col[2], 0.55);
        }
      }
    }
    points.grow(N);
    const globe = projName === 'sphere';
    for (let b = 0; b < N; b++) {
      toScreen(proj[3 * b], proj[3 * b + 1], proj[3 * b + 2], s);
      scr[3 * b] = s[0]; scr[3 * b + 1] = s[1]; scr[3 * b + 2] = s[2];
      scrVis[b] = vis[b];
    }
    // 3-D: painter's order, far (depth < 0 is behind the centre) first; the globe's far side is dimmed.
    let order = null;
    if (camera) {
      order = new Uint32Array(N);
      for (let b = 0; b < N; b++) order[b] = b;
      order.sort((i, j) => scr[3 * i + 2] - scr[3 * j + 2]);
    }
    for (let i = 0; i < N; i++) {
      const b = order ? order[i] : i;
      if (!vis[b]) continue;
      bodyColour(fr, b, col);
      const al = camera && scr[3 * b + 2] < 0 ? (globe ? 0.3 : 0.8) : 1;
      points.push(scr[3 * b], scr[3 * b + 1], pointSize(proj[3 * b], proj[3 * b + 1], proj[3 * b + 2]),
                  col[0], col[1], col[2], al);
    }
  }

  function updateText(fr) {
    const s = meta.space;
    const parts = [state.space];
    if (s.kind !== 'euclidean') parts.push('R = ' + fmt(s.radius));
    if (s.box) parts.push('box ' + s.box.map(fmt).join(' x '));
    if (s.genus) parts.push('genus ' + s.genus + ' surface');
    parts.push(view.label + (view.note ? ' (' + view.note + ')' : ''));
    parts.push(F > 0 ? 't = ' + fmt(meta.frames.t[current]) : 'no frames');
    if (F > 0) parts.push('frame ' + (current + 1) + '/' + F + (meta.frames.thinned_from ? ' (of ' + meta.frames.thinned_from + ' written)' : ''));
    parts.push(N + (N === 1 ? ' body' : ' bodies'));
    $('what').textContent = '\u2014 ' + parts.join(' \u00b7 ');
    $('title').textContent = meta.title || 'sesi view';
    document.title = (meta.title || 'sesi') + ' \u2014 sesi view';
    const slider = $('slider');
    if (Number(slider.value) !== current) slider.value = String(current);
    $('play').innerHTML = playing ? '&#10074;&#10074;' : '&#9654;';
    // Legend of the colour range (speed, energy).
    const lg = $('legend');
    const ranged = colourMode !== 'body' && meta.frames.speed;
    lg.hidden = !ranged;
    if (ranged) {
      $('legend-lo').textContent = '0';
      $('legend-hi').textContent = fmt(colourMode === 'speed' ? speedMax : energyMax);
      $('legend-name').textContent = colourMode === 'speed' ? 'speed |v|' : 'kinetic energy m|v|\u00b2/2';
      const bar = $('legend-bar'), g = bar.getContext('2d');
      for (let x = 0; x < bar.width; x++) {
        const c = G.colourmap('viridis', x / (bar.width - 1));
        g.fillStyle = 'rgb(' + c[0] + ',' + c[1] + ',' + c[2] + ')';
        g.fillRect(x, 0, 1, bar.height);
      }
    }
    drawDiagnostics();
  }

  function fillState(fr) {
    const r = canvas.getBoundingClientRect();
    state.frame = current;
    state.frames = F;
    state.t = F > 0 ? meta.frames.t[current] : 0;
    state.canvas = { left: r.left, top: r.top, width: r.width, height: r.height };
    // Canvas CSS size may differ from the drawing size only by the border; positions are inside the border.
    const bx = r.left + canvas.clientLeft, by = r.top + canvas.clientTop;
    state.origin = [bx + ox, by + oy];
    state.scale = sc;
    state.camera = camera ? Array.from(camera) : null;
    state.isometry = Array.from(iso.m).concat(iso.t ? Array.from(iso.t) : []);
    state.screen = [];
    state.colours = [];
    if (fr && scr) {
      const n = Math.min(N, 256), col = [0, 0, 0];
      for (let b = 0; b < n; b++) {
        state.screen.push([bx + scr[3 * b], by + scr[3 * b + 1], scrVis[b] ? 1 : 0]);
        bodyColour(fr, b, col);
        state.colours.push([Math.round(255 * col[0]), Math.round(255 * col[1]), Math.round(255 * col[2])]);
      }
      state.point_px = N > 0 ? pointSize(proj[0], proj[1], proj[2]) : 0;
    }
  }

  // ---------------------------------------------------------------- diagnostics panel
  let diagBoxes = [];
  function buildDiagnostics() {
    const box = $('diagnostics');
    box.textContent = '';
    diagBoxes = [];
    const series = meta.diagnostics && Array.isArray(meta.diagnostics.series) ? meta.diagnostics.series : [];
    for (const s of series) {
      if (!s || !Array.isArray(s.t) || !Array.isArray(s.y) || s.t.length !== s.y.length || s.t.length === 0) continue;
      const d = document.createElement('div');
      d.className = 'series';
      const label = document.createElement('div');
      const c = document.createElement('canvas');
      d.appendChild(label);
      d.appendChild(c);
      box.appendChild(d);
      let lo = Infinity, hi = -Infinity, t0 = Infinity, t1 = -Infinity;
      for (let i = 0; i < s.y.length; i++) {
        const y = s.y[i], t = s.t[i];
        if (Number.isFinite(y)) { lo = Math.min(lo, y); hi = Math.max(hi, y); }
        if (Number.isFinite(t)) { t0 = Math.min(t0, t); t1 = Math.max(t1, t); }
      }
      if (F > 0) { t0 = Math.min(t0, meta.frames.t[0]); t1 = Math.max(t1, meta.frames.t[F - 1]); }
      label.textContent = s.name + '  [' + fmt(lo) + ', ' + fmt(hi) + ']';
      const entry = { s: s, c: c, lo: lo, hi: hi, t0: t0, t1: t1 };
      diagBoxes.push(entry);
      c.addEventListener('click', (ev) => {
        const r = c.getBoundingClientRect();
        const t = entry.t0 + (ev.clientX - r.left) / r.width * (entry.t1 - entry.t0);
        seek(nearestFrame(t));
      });
    }
  }

  function nearestFrame(t) {
    const ts = meta.frames.t;
    let lo = 0, hi = F - 1;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (ts[mid] <= t) lo = mid; else hi = mid;
    }
    return Math.abs(ts[hi] - t) < Math.abs(ts[lo] - t) ? hi : lo;
  }

  function drawDiagnostics() {
    for (const e of diagBoxes) {
      const c = e.c, w = c.clientWidth, h = c.clientHeight;
      if (w <= 0 || h <= 0) continue;
      if (c.width !== Math.round(w * dpr)) { c.width = Math.round(w * dpr); c.height = Math.round(h * dpr); }
      const g = c.getContext('2d');
      g.setTransform(dpr, 0, 0, dpr, 0, 0);
      g.clearRect(0, 0, w, h);
      const span = e.t1 - e.t0 || 1, yspan = e.hi - e.lo || 1;
      const X = (t) => (t - e.t0) / span * (w - 4) + 2, Y = (y) => h - 4 - (y - e.lo) / yspan * (h - 8);
      g.strokeStyle = '#7fb2e5';
      g.lineWidth = 1.25;
      g.beginPath();
      let started = false;
      for (let i = 0; i < e.s.t.length; i++) {
        const y = e.s.y[i];
        if (!Number.isFinite(y)) { started = false; continue; }
        if (started) g.lineTo(X(e.s.t[i]), Y(y)); else { g.moveTo(X(e.s.t[i]), Y(y)); started = true; }
      }
      g.stroke();
      if (F > 0) {
        g.strokeStyle = '#ffd27f';
        g.beginPath();
        const x = X(meta.frames.t[current]);
        g.moveTo(x, 0);
        g.lineTo(x, h);
        g.stroke();
      }
    }
  }

  // tools/view_bench.py (bench=K): the time of a redraw of the frame shown (projection, buffers,
  // drawing; gl.finish() waits for the GPU), and of a step to each of the next K frames (decoding
  // too), averaged over K; into state.bench. Then back to the frame asked for.
  function benchmark(k) {
    if (!(k > 0) || F === 0) return;
    const finish = () => { if (gl) gl.finish(); };
    const start = current;
    let t0 = performance.now();
    for (let i = 0; i < k; i++) { draw(); finish(); }
    const redraw = (performance.now() - t0) / k;
    const steps = Math.min(k, F - 1);
    t0 = performance.now();
    for (let i = 1; i <= steps; i++) { current = (start + i) % F; draw(); finish(); }
    const step = steps > 0 ? (performance.now() - t0) / steps : null;
    current = start;
    draw();
    state.bench = { bodies: N, redraws: k, redraw_ms: redraw, steps: steps, step_ms: step };
    writeState();
  }

  // ---------------------------------------------------------------- interaction
  function seek(k) {
    if (F === 0) return;
    k = Math.max(0, Math.min(F - 1, Math.round(k)));
    current = k;
    drawSafe();
  }

  let lastTick = 0;
  const FPS = 12;  // playback frames per second
  function tick(now) {
    if (!playing) return;
    if (now - lastTick >= 1000 / FPS) {
      lastTick = now;
      // In stream mode wait for the frame on screen before moving on.
      if (!meta.frames.stream || cache.has(current) || failed.has(current)) {
        current = (current + 1) % F;
        drawSafe();
        if (meta.frames.stream && F > 1) fetchFrame((current + 1) % F);  // the next one, ahead of time
      }
    }
    requestAnimationFrame(tick);
  }

  function play(on) {
    playing = !!on && F > 1;
    if (playing) { lastTick = 0; requestAnimationFrame(tick); }
    updateText(F > 0 ? cache.get(current) : null);
    writeState();
  }

  function bodyAt(clientX, clientY) {
    if (!scr) return -1;
    const r = canvas.getBoundingClientRect();
    const x = clientX - r.left - canvas.clientLeft, y = clientY - r.top - canvas.clientTop;
    let best = -1, bd = 12 * 12;  // within 12 px of the pointer
    for (let b = 0; b < N; b++) {
      if (!scrVis[b]) continue;
      const dx = scr[3 * b] - x, dy = scr[3 * b + 1] - y, d = dx * dx + dy * dy;
      if (d < bd && (!camera || scr[3 * b + 2] >= 0 || best < 0)) { bd = d; best = b; }
    }
    return best;
  }

  function centreOn(b) {
    if (!(b >= 0 && b < N) || F === 0) return false;
    const fr = getFrame(current);
    if (!fr) return false;
    const x = new Float64Array(A);
    for (let i = 0; i < A; i++) x[i] = fr.x[A * b + i];
    iso = view.centreOn(x);
    pole = '';
    if ($('pole')) $('pole').value = '';
    // The globe: turn the camera to face the north pole, where the body now is (drawn at the middle).
    if (projName === 'sphere' && camera) camera = Float64Array.of(1, 0, 0, 0, 1, 0, 0, 0, 1);
    drawSafe();
    return true;
  }

  function rotateCamera(ax, ay) {
    // Turn about the screen's y axis by ax and its x axis by ay (radians), applied after the camera.
    const cy = Math.cos(ax), sy = Math.sin(ax), cx = Math.cos(ay), sx = Math.sin(ay);
    const Ry = [cy, 0, sy, 0, 1, 0, -sy, 0, cy];
    const Rx = [1, 0, 0, 0, cx, -sx, 0, sx, cx];
    camera = mul3(Rx, mul3(Ry, camera));
  }

  function wire() {
    const sel = $('projection');
    for (const name of G.projections(meta.space)) {
      const o = document.createElement('option');
      o.value = name;
      o.textContent = name;
      sel.appendChild(o);
    }
    sel.value = projName;
    sel.addEventListener('change', () => { setView(sel.value); drawSafe(); });
    const colSel = $('colour');
    if (!meta.frames.speed) {
      for (const o of colSel.options) if (o.value !== 'body') { o.disabled = true; o.textContent += ' (no speeds)'; }
    }
    colSel.value = colourMode;
    colSel.addEventListener('change', () => { colourMode = colSel.value; drawSafe(); });
    const tr = $('trail');
    tr.value = String(trail);
    tr.addEventListener('change', () => { trail = Math.max(0, Math.min(1000, Math.round(num(tr.value, 0)))); drawSafe(); });
    const sz = $('size');
    sz.value = String(sizeFactor);
    sz.addEventListener('input', () => { sizeFactor = num(sz.value, 1); drawSafe(); });
    const ps = $('pole');
    const specs = poleSpecs();
    $('pole-label').hidden = specs.length === 0;
    const picked = document.createElement('option');
    picked.value = '';
    picked.textContent = 'a body (double-click)';
    picked.disabled = true;
    ps.appendChild(picked);
    for (const spec of specs) {
      const o = document.createElement('option');
      o.value = spec;
      o.textContent = poleLabel(spec);
      ps.appendChild(o);
    }
    ps.value = pole || '+' + A;
    ps.addEventListener('change', () => { setPole(ps.value); drawSafe(); });
    const axesField = $('axes');
    $('axes-label').hidden = !(meta.space.dim > 3);
    axesField.value = (axes || [0, 1, 2]).map((k) => k + 1).join(',');
    axesField.addEventListener('change', () => {
      if (!setAxes(axesField.value)) {
        banner('axes: three different coordinates of 1..' + meta.space.dim + ', e.g. 1,2,3 (got "' + axesField.value +
               '").', true);
        axesField.value = (axes || [0, 1, 2]).map((k) => k + 1).join(',');
      }
      drawSafe();
    });
    const tl = $('tiles');
    $('tiles-label').hidden = !meta.polygon;
    tl.checked = tilesOn;
    tl.addEventListener('change', () => { tilesOn = tl.checked; drawSafe(); });
    const slider = $('slider');
    slider.max = String(Math.max(0, F - 1));
    slider.value = String(current);
    slider.addEventListener('input', () => seek(Number(slider.value)));
    $('play').addEventListener('click', () => play(!playing));
    $('prev').addEventListener('click', () => seek(current - 1));
    $('next').addEventListener('click', () => seek(current + 1));
    $('recentre').addEventListener('click', () => {
      iso = view.identity();
      pole = '';
      if (specs.length) ps.value = '+' + A;
      drawSafe();
    });
    // Buttons give the focus back, so that the space bar (play/pause) does not also press them.
    for (const id of ['play', 'prev', 'next', 'recentre']) $(id).addEventListener('click', (ev) => ev.currentTarget.blur());

    document.addEventListener('keydown', (ev) => {
      const t = ev.target;
      if (t && (t.tagName === 'SELECT' || (t.tagName === 'INPUT' && t.type !== 'checkbox' && t.type !== 'range'))) return;
      if (ev.key === ' ' || ev.code === 'Space') { ev.preventDefault(); play(!playing); }
      else if (t && t.tagName === 'INPUT' && t.type === 'range') return;  // a slider keeps its own arrow keys
      else if (ev.key === 'ArrowLeft') { ev.preventDefault(); seek(current - 1); }
      else if (ev.key === 'ArrowRight') { ev.preventDefault(); seek(current + 1); }
    });

    let drag = null;
    canvas.addEventListener('pointerdown', (ev) => {
      if (ev.button !== 0) return;
      if (ev.shiftKey || ev.altKey || ev.ctrlKey || ev.metaKey) {
        const b = bodyAt(ev.clientX, ev.clientY);
        if (b >= 0) centreOn(b);
        return;
      }
      drag = { x: ev.clientX, y: ev.clientY };
      canvas.classList.add('dragging');
      try { canvas.setPointerCapture(ev.pointerId); } catch (e) { /* not every pointer can be captured */ }
    });
    canvas.addEventListener('pointermove', (ev) => {
      if (!drag) return;
      const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
      drag.x = ev.clientX;
      drag.y = ev.clientY;
      if (dx === 0 && dy === 0) return;
      if (camera) rotateCamera(dx * 0.01, dy * 0.01);
      else iso = view.drag(iso, dx / sc, -dy / sc);
      scheduleDraw();
    });
    const end = () => { drag = null; canvas.classList.remove('dragging'); };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('dblclick', (ev) => {
      const b = bodyAt(ev.clientX, ev.clientY);
      if (b >= 0) centreOn(b);
    });
    canvas.addEventListener('wheel', (ev) => {
      ev.preventDefault();
      zoom *= Math.exp(-ev.deltaY * 0.001);
      zoom = Math.min(1e4, Math.max(1e-3, zoom));
      scheduleDraw();
    }, { passive: false });
    window.addEventListener('resize', () => { layout(); scheduleDraw(); });
  }

  // ---------------------------------------------------------------- start
  function start() {
    if (!G) throw new Error('The page is incomplete: its geometry code (SesiGeometry) is missing.');
    meta = readMeta();
    N = meta.bodies;
    A = meta.ambient;
    F = meta.frames.count;
    if (!Array.isArray(meta.masses)) meta.masses = [];
    state.space = G.spaceLabel(meta.space);
    state.frames = F;
    if (meta.complete === false) {
      banner('This run did not finish: ' + (meta.status || 'no reason given') + '. Showing the frames it wrote.');
    }
    if (F === 0) banner('This run wrote no frames.');
    if (!meta.frames.stream) {
      indexFrames();
      if (F > 0 && lineStart.length !== F) {
        banner('The page holds ' + lineStart.length + ' frame lines, but its run data says ' + F + ' frames' +
               (lineStart.length < F ? ': showing the ones present.' : '.'));
        F = Math.min(F, lineStart.length);
      }
    }
    bodyCols = new Float32Array(3 * N);
    for (let b = 0; b < N; b++) {
      const c = G.bodyColour(b);
      bodyCols[3 * b] = c[0] / 255; bodyCols[3 * b + 1] = c[1] / 255; bodyCols[3 * b + 2] = c[2] / 255;
    }
    // Parameters.
    const names = G.projections(meta.space);
    if (params.projection !== undefined && names.indexOf(params.projection) < 0) {
      banner('Unknown projection "' + params.projection + '" for ' + state.space + ': showing ' + names[0] +
             ' (choices: ' + names.join(', ') + ').', true);
    }
    if (params.axes !== undefined) {
      if (!(meta.space.dim > 3)) banner('axes=' + params.axes + ': only a space of dimension above 3 has coordinates to choose.', true);
      else if (!(axes = parseAxes(params.axes))) {
        banner('axes=' + params.axes + ' is not three different coordinates of 1..' + meta.space.dim + ': showing 1,2,3.', true);
      }
    }
    setView(params.projection);
    current = F > 0 ? Math.max(0, Math.min(F - 1, Math.round(num(params.frame, 0)))) : 0;
    colourMode = ['body', 'speed', 'energy'].indexOf(params.colour) >= 0 ? params.colour : 'body';
    if (colourMode !== 'body' && !meta.frames.speed) {
      banner('This run has no speeds: colouring by body.', true);
      colourMode = 'body';
    }
    trail = Math.max(0, Math.min(1000, Math.round(num(params.trail, 0))));
    sizeFactor = Math.max(0.05, num(params.size, 1));
    tilesOn = params.tiles === '1' && !!meta.polygon;
    initRenderer();
    wire();
    buildDiagnostics();
    layout();
    if (params.pole !== undefined) {
      const given = params.pole.trim();  // an unescaped '+' in a query reads as a space
      const spec = /^\d/.test(given) ? '+' + given : given;
      if (!setPole(spec)) {
        banner('pole=' + params.pole + ' is not an axis pole of ' + state.space + ' (' +
               (poleSpecs().join(', ') || 'only S^n has poles to choose') + ').', true);
      }
    }
    if (params.centre !== undefined) {
      const b = Math.round(num(params.centre, -1));
      if (!(b >= 0 && b < N)) banner('centre=' + params.centre + ' is not a body (0 to ' + (N - 1) + ').', true);
      else if (!meta.frames.stream) centreOn(b);
      else {
        // Stream mode: centre once the frame has arrived.
        fetchFrame(current);
        const p = pending.get(current);
        if (p) p.then(() => centreOn(b));
      }
    }
    draw();  // synchronously: --dump-dom and --screenshot see the first frame
    if (params.bench !== undefined) benchmark(Math.round(num(params.bench, 0)));
    // Headless browsers may size the window after the first layout without a resize event: follow it.
    const seen = [window.innerWidth, window.innerHeight];
    requestAnimationFrame(() => {
      if (window.innerWidth !== seen[0] || window.innerHeight !== seen[1]) { layout(); drawSafe(); }
    });
    if (params.play === '1') play(true);
  }

  window.sesiView = {
    state: () => JSON.parse(JSON.stringify(state)),
    setFrame: (k) => { seek(k); return state.frame; },
    setProjection: (name) => { if (!meta) return false; setView(name); drawSafe(); return state.projection === name; },
    centreOn: (b) => centreOn(b),
    play: (on) => play(on === undefined ? true : on)
  };

  function boot() {
    try {
      start();
    } catch (e) {
      const msg = e && e.message ? e.message : String(e);
      if (e instanceof DataError) banner(msg); else recordError(msg);
    }
    writeState();
  }
  // The script comes last in the page's body: its elements exist, so draw now (not at DOMContentLoaded).
  if (document.readyState !== 'loading' || ($('sesi-state') && $('controls') && $('diagnostics'))) boot();
  else document.addEventListener('DOMContentLoaded', boot);
})();
