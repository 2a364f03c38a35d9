// atlasmesh's 3D viewer: WebGL 1, no library, no network. Every `div.am-viewer` of the page
// names (data-scene) a <script type="application/json"> holding its scene: layers of points
// (surfaces by triangles, meshes by cells with their faces), values per point or per cell,
// colour fields, the worst elements, and (on the model page) the modes' displacements. Binary
// arrays arrive gzip-compressed and base64-encoded (little-endian Float32 / Uint32, or Int16
// times a scale).
//
// The viewer records its state on its container for tests and for the curious:
// data-state ("drawn", "no-webgl", "error: ..."), data-triangles, data-drawn-pixels (the
// pixels of the first frame that are not background), data-ready-ms (when the first frame
// was drawn, from the page's start).
//
// The scene's JSON is Rust's `report::viewer_scene::SceneJson` (version 1); the typedefs
// below name the same fields, and CI type-checks this file against them (scripts/js).
// Rust pairs the faces between cells, samples the colour maps and writes no markup: labels
// reach the page as text.
// @ts-check

/**
 * @typedef {Float32Array | Uint32Array} Arr  an array once decoded
 * @typedef {{lut: number[][], below: number[], nan: number[]}} ColorMap  256 RGB bytes
 * @typedef {{jacobian: ColorMap, distance: ColorMap, magnitude: ColorMap}} ColorMaps
 * @typedef {{id: string, label: string, unit: string, lo: number, hi: number,
 *   map: 'jacobian' | 'distance' | 'magnitude'}} Field
 * @typedef {{nodes_per_cell: number, corners: number, faces: number[][], nodes: Uint32Array,
 *   face_slot_steps: Uint32Array, face_other_steps: Uint32Array}} Cells
 * @typedef {{id: string, label: string, visible: boolean, opacity: number, color: number[],
 *   positions: Float32Array, worst: number[], triangles?: Uint32Array, segments?: Uint32Array,
 *   cells?: Cells, point_values: Object<string, Float32Array>,
 *   cell_values: Object<string, Float32Array>, centroids?: Float32Array}} Layer
 * @typedef {{sd: number[], max_sd: number, displacements: Object<string, Float32Array[]>,
 *   max_displacement: number[]}} Modes
 * @typedef {{version: number, dimension: number, layers: Layer[], fields: Field[],
 *   view: {look: number[], up: number[]}, colormaps: ColorMaps, modes?: Modes}} Scene
 */
(function () {
  'use strict';

  function b64bytes(s) {
    var bin = atob(s);
    var out = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }

  function gunzip(bytes) {
    var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'));
    return new Response(stream).arrayBuffer();
  }

  // Decodes every {"f32": ...} / {"u32": ...} of `obj` in place; resolves when all are done.
  function decode(obj) {
    var jobs = [];
    (function walk(o) {
      if (!o || typeof o !== 'object') return;
      Object.keys(o).forEach(function (k) {
        var v = o[k];
        if (v && typeof v === 'object' && typeof v.i16 === 'string') {
          jobs.push(gunzip(b64bytes(v.i16)).then(function (buf) {
            var q = new Int16Array(buf), out = new Float32Array(q.length), s = v.scale;
            for (var i = 0; i < q.length; i++) out[i] = q[i] * s;
            o[k] = out;
          }));
        } else if (v && typeof v === 'object' && (typeof v.f32 === 'string' || typeof v.u32 === 'string')) {
          var f = typeof v.f32 === 'string';
          jobs.push(gunzip(b64bytes(f ? v.f32 : v.u32)).then(function (buf) {
            o[k] = f ? new Float32Array(buf) : new Uint32Array(buf);
          }));
        } else {
          walk(v);
        }
      });
    })(obj);
    return Promise.all(jobs).then(function () { return obj; });
  }

  // The colour of value `v` of `field`, from the scene's sampled maps (Rust's, the PNG
  // pictures' own): RGB in 0..1.
  /** @param {ColorMaps} maps @param {Field} field @param {number} v @returns {number[]} */
  function colorOf(maps, field, v) {
    var m = maps[field.map], c;
    if (field.map === 'jacobian') {
      c = !(v > 0) ? (v <= 0 ? m.below : m.nan) : m.lut[Math.round(Math.min(v, 1) * 255)];
    } else {
      var t = (v - field.lo) / Math.max(field.hi - field.lo, 1e-300);
      c = isFinite(t) ? m.lut[Math.round(Math.max(0, Math.min(1, t)) * 255)] : m.nan;
    }
    return [c[0] / 255, c[1] / 255, c[2] / 255];
  }

  // 4x4 matrices, column-major as WebGL takes them.
  function perspective(fovy, aspect, near, far) {
    var f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0];
  }
  function mul(a, b) {
    var o = new Array(16);
    for (var c = 0; c < 4; c++) for (var r = 0; r < 4; r++) {
      var s = 0;
      for (var k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      o[c * 4 + r] = s;
    }
    return o;
  }
  function norm3(v) {
    var l = Math.hypot(v[0], v[1], v[2]) || 1;
    return [v[0] / l, v[1] / l, v[2] / l];
  }
  function cross(a, b) {
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  }

  var VS = 'attribute vec3 pos; attribute vec3 nrm; attribute vec3 col;' +
    'uniform mat4 mvp; uniform vec3 eye; uniform vec4 clip; uniform float clipOn;' +
    'varying vec3 vCol; varying vec3 vN; varying vec3 vV; varying float vClip;' +
    'void main() { gl_Position = mvp * vec4(pos, 1.0); vCol = col; vN = nrm; vV = eye - pos;' +
    ' vClip = clipOn * (dot(clip.xyz, pos) - clip.w); }';
  var FS = 'precision mediump float; varying vec3 vCol; varying vec3 vN; varying vec3 vV;' +
    'varying float vClip; uniform float lit; uniform float alpha;' +
    'void main() { if (vClip > 0.0) discard;' +
    ' float l = 1.0; if (lit > 0.5) { l = 0.3 + 0.7 * abs(dot(normalize(vN), normalize(vV))); }' +
    ' gl_FragColor = vec4(vCol * l, alpha); }';

  /** @constructor @param {HTMLElement} root @param {Scene} scene */
  function Viewer(root, scene) {
    this.root = root;
    this.scene = scene;
    this.fieldById = {};
    var self = this;
    scene.fields.forEach(function (f) { self.fieldById[f.id] = f; });
    this.field = scene.fields.length ? scene.fields[0].id : null;
    this.clip = { on: false, axis: scene.dimension === 3 ? 2 : 0, at: 0.5 };
    this.worst = true;
    this.mode = { k: 0, w: 0 };
    var side = this.fromHash();
    this.build();
    this.prepare();
    this.camera = null;
    this.reset(side);
    this.update();
  }

  // A view named in the page's address: #clip=AXIS,AT (axis 0-2, AT in 0..1 of the extent),
  // color=FIELD, mode=K,W (mode K from 1, W in sd), side=back; e.g.
  // NAME.html#clip=2,0.5&color=distance. Returns the side to look from.
  Viewer.prototype.fromHash = function () {
    var side = 1, self = this;
    (location.hash || '').replace(/^#/, '').split('&').forEach(function (kv) {
      var p = kv.split('='), v = (p[1] || '').split(',');
      if (p[0] === 'clip' && v.length === 2) {
        self.clip = { on: true, axis: Math.max(0, Math.min(2, Math.trunc(Number(v[0])) || 0)), at: Math.max(0, Math.min(1, +v[1] || 0)) };
      } else if (p[0] === 'color' && Object.prototype.hasOwnProperty.call(self.fieldById, p[1])) {
        self.field = p[1];
      } else if (p[0] === 'mode' && v.length === 2 && self.scene.modes) {
        self.mode = { k: Math.max(0, Math.min(self.scene.modes.sd.length - 1, (Math.trunc(Number(v[0])) || 0) - 1)), w: +v[1] || 0 };
      } else if (p[0] === 'side' && p[1] === 'back') {
        side = -1;
      }
    });
    return side;
  };

  // An element `tag` with attributes `attrs` and children (elements, or strings as text).
  /** @param {string} tag @param {Object<string, string>} attrs @param {Array<Node|string>} [children] @returns {HTMLElement} */
  function el(tag, attrs, children) {
    var e = document.createElement(tag);
    Object.keys(attrs).forEach(function (k) { e.setAttribute(k, attrs[k]); });
    (children || []).forEach(function (c) { e.appendChild(typeof c === 'string' ? document.createTextNode(c) : c); });
    return e;
  }
  /** @param {HTMLElement} e @returns {HTMLInputElement} */
  function input(e) { return /** @type {HTMLInputElement} */ (e); }

  Viewer.prototype.build = function () {
    var self = this, s = this.scene, root = this.root;
    root.textContent = '';
    var canvas = /** @type {HTMLCanvasElement} */ (el('canvas', {
      class: 'am-canvas',
      'aria-label': 'interactive 3D view: drag to rotate, right-drag or shift-drag to pan, wheel to zoom'
    }));
    canvas.width = Number(root.getAttribute('data-width')) || 720;
    canvas.height = Number(root.getAttribute('data-height')) || 480;
    var panel = el('div', { class: 'am-panel' });
    root.appendChild(canvas);
    root.appendChild(panel);
    this.canvas = canvas;
    var gl = /** @type {WebGLRenderingContext} */ (
      canvas.getContext('webgl', { preserveDrawingBuffer: true, antialias: true }) ||
      canvas.getContext('experimental-webgl', { preserveDrawingBuffer: true }));
    if (!gl) throw new Error('no-webgl');
    this.gl = gl;
    /** @param {Array<Node|string>} children @returns {HTMLElement} */
    function add(children) { var d = el('div', {}, children); panel.appendChild(d); return d; }
    // Layers.
    s.layers.forEach(function (l) {
      var box = input(el('input', { type: 'checkbox' }));
      box.checked = l.visible;
      box.addEventListener('change', function () { l.visible = box.checked; self.update(); });
      add([el('label', {}, [box, ' ' + l.label])]);
    });
    // Colour.
    if (s.fields.length) {
      var select = /** @type {HTMLSelectElement} */ (el('select', {}, s.fields.map(function (f) {
        return el('option', { value: f.id }, [f.label + (f.unit ? ' (' + f.unit + ')' : '')]);
      })));
      select.value = this.field;
      select.addEventListener('change', function () { self.field = select.value; self.update(); });
      add([el('label', {}, ['colour by ', select])]);
    }
    // Clipping plane.
    var hasCells = s.layers.some(function (l) { return !!l.cells; });
    var clipOn = input(el('input', { type: 'checkbox', class: 'am-clip' }));
    var axis = /** @type {HTMLSelectElement} */ (el('select', { class: 'am-axis' }, ['x', 'y', 'z'].map(function (a, i) {
      return el('option', { value: String(i) }, [a]);
    })));
    var at = input(el('input', { type: 'range', class: 'am-at', min: '0', max: '1000', value: '500' }));
    add([el('label', {}, [clipOn, ' clip ' + (hasCells ? 'through the volume' : '')]), ' ', axis, ' ', at]);
    clipOn.checked = this.clip.on;
    axis.value = String(this.clip.axis);
    at.value = String(Math.round(this.clip.at * 1000));
    clipOn.addEventListener('change', function () { self.clip.on = clipOn.checked; self.update(); });
    axis.addEventListener('change', function () { self.clip.axis = +axis.value; self.update(); });
    at.addEventListener('input', function () { self.clip.at = +at.value / 1000; self.update(); });
    if (s.layers.some(function (l) { return l.worst && l.worst.length; })) {
      var worst = input(el('input', { type: 'checkbox' }));
      worst.checked = true;
      worst.addEventListener('change', function () { self.worst = worst.checked; self.update(); });
      add([el('label', {}, [worst, ' worst elements (magenta)'])]);
    }
    // Modes.
    if (s.modes && s.modes.sd.length) {
      var mx = s.modes.max_sd || 3;
      var mode = /** @type {HTMLSelectElement} */ (el('select', { class: 'am-mode' }, s.modes.sd.map(function (_, k) {
        return el('option', { value: String(k) }, ['mode ' + (k + 1)]);
      })));
      var slider = input(el('input', { type: 'range', class: 'am-w', min: String(-mx), max: String(mx), step: '0.1', value: '0' }));
      var shown = el('span', { class: 'am-wv' }, ['0.0 σ']);
      var label = function () { shown.textContent = (self.mode.w >= 0 ? '+' : '') + self.mode.w.toFixed(1) + ' σ'; };
      add([mode, ' ', slider, ' ', shown]);
      mode.addEventListener('change', function () { self.mode.k = +mode.value; self.update(); });
      slider.addEventListener('input', function () { self.mode.w = +slider.value; label(); self.update(); });
      this.modeSlider = slider;
      mode.value = String(this.mode.k);
      slider.value = String(this.mode.w);
      label();
    }
    var views = [1, -1].map(function (v) {
      var b = el('button', { type: 'button', 'data-v': String(v) }, [v > 0 ? 'front' : 'back']);
      b.addEventListener('click', function () { self.reset(v); self.draw(); });
      return b;
    });
    add([views[0], ' ', views[1]]);
    this.legend = add([]);
    this.legend.className = 'am-legend';
    this.info = add([]);
    this.info.className = 'am-info';
    this.mouse();
  };

  // Per cell layer: the centroids of its cells (the clipping plane keeps or removes whole
  // cells); and the bounding box of everything.
  Viewer.prototype.prepare = function () {
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    this.scene.layers.forEach(function (l) {
      var p = l.positions;
      for (var i = 0; i < p.length; i += 3) for (var d = 0; d < 3; d++) {
        if (p[i + d] < lo[d]) lo[d] = p[i + d];
        if (p[i + d] > hi[d]) hi[d] = p[i + d];
      }
      var C = l.cells;
      if (!C) return;
      var k = C.nodes_per_cell, n = C.nodes.length / k, corners = C.corners || k;
      l.centroids = new Float32Array(n * 3);
      for (var c = 0; c < n; c++) {
        for (var j = 0; j < corners; j++) {
          var v = C.nodes[c * k + j];
          for (var d2 = 0; d2 < 3; d2++) l.centroids[c * 3 + d2] += p[v * 3 + d2] / corners;
        }
      }
    });
    this.lo = lo;
    this.hi = hi;
    this.center = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
    this.radius = Math.max(Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2, 1e-9);
    var gl = this.gl;
    function shader(type, src) {
      var sh = gl.createShader(type);
      gl.shaderSource(sh, src);
      gl.compileShader(sh);
      if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(sh));
      return sh;
    }
    var prog = gl.createProgram();
    gl.attachShader(prog, shader(gl.VERTEX_SHADER, VS));
    gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, FS));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog));
    this.prog = prog;
    this.loc = {};
    var self = this;
    ['pos', 'nrm', 'col'].forEach(function (a) { self.loc[a] = gl.getAttribLocation(prog, a); });
    ['mvp', 'eye', 'clip', 'clipOn', 'lit', 'alpha'].forEach(function (u) { self.loc[u] = gl.getUniformLocation(prog, u); });
    this.buffers = [];
  };

  // The camera: it looks at `target` from `dist` away along the direction given by `yaw` and
  // `pitch` of the scene's frame; for 2D, straight down the z axis.
  Viewer.prototype.reset = function (side) {
    var s = this.scene;
    var v = s.view || { look: [0, 0, -1], up: [0, 1, 0] };
    var look = norm3(v.look), up = norm3(v.up);
    if (side < 0) look = [-look[0], -look[1], -look[2]];
    // Centred on the shown layers' points as seen, far enough for all of them to fit the
    // canvas, with a margin.
    var right = norm3(cross(look, up)), axes = [right, up, look];
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    var layers = this.scene.layers.filter(function (l) { return l.visible; });
    if (!layers.length) layers = this.scene.layers;
    layers.forEach(function (l) {
      var p = l.positions, n = p.length / 3, step = Math.max(1, Math.floor(n / 20000));
      for (var i = 0; i < n; i += step) {
        for (var a = 0; a < 3; a++) {
          var v = p[3 * i] * axes[a][0] + p[3 * i + 1] * axes[a][1] + p[3 * i + 2] * axes[a][2];
          if (v < lo[a]) lo[a] = v;
          if (v > hi[a]) hi[a] = v;
        }
      }
    });
    var mid = [0, 1, 2].map(function (a) { return isFinite(lo[a]) ? (lo[a] + hi[a]) / 2 : 0; });
    var c = [0, 1, 2].map(function (d) { return mid[0] * right[d] + mid[1] * up[d] + mid[2] * look[d]; });
    var hx = (hi[0] - lo[0]) / 2 || 0, hy = (hi[1] - lo[1]) / 2 || 0, hz = (hi[2] - lo[2]) / 2 || 0;
    var aspect = this.canvas.width / this.canvas.height;
    var half = Math.max(hy, hx / aspect, 1e-9 * this.radius) * 1.08;
    this.camera = { target: c, look: look, up: up, dist: half / Math.tan(Math.PI / 12) + hz };
  };

  Viewer.prototype.mouse = function () {
    var self = this, c = this.canvas, last = null, button = 0;
    c.addEventListener('contextmenu', function (e) { e.preventDefault(); });
    c.addEventListener('mousedown', function (e) { last = [e.clientX, e.clientY]; button = (e.button === 2 || e.shiftKey) ? 2 : 0; e.preventDefault(); });
    window.addEventListener('mouseup', function () { last = null; });
    window.addEventListener('mousemove', function (e) {
      if (!last) return;
      var dx = e.clientX - last[0], dy = e.clientY - last[1];
      last = [e.clientX, e.clientY];
      var cam = self.camera, right = norm3(cross(cam.look, cam.up));
      if (button === 2) {
        var k = 2 * cam.dist * Math.tan(Math.PI / 12) / c.clientHeight;
        for (var d = 0; d < 3; d++) cam.target[d] += (-dx * right[d] + dy * cam.up[d]) * k;
      } else {
        self.rotate(cam.up, -dx * 0.01);
        self.rotate(right, -dy * 0.01);
      }
      self.draw();
    });
    c.addEventListener('wheel', function (e) {
      e.preventDefault();
      self.camera.dist *= Math.exp(e.deltaY * 0.001);
      self.draw();
    }, { passive: false });
  };

  // Turns the camera by `angle` about `axis` (through the target).
  Viewer.prototype.rotate = function (axis, angle) {
    var a = norm3(axis), cs = Math.cos(angle), sn = Math.sin(angle);
    function rot(v) {
      var d = a[0] * v[0] + a[1] * v[1] + a[2] * v[2], x = cross(a, v);
      return [v[0] * cs + x[0] * sn + a[0] * d * (1 - cs), v[1] * cs + x[1] * sn + a[1] * d * (1 - cs), v[2] * cs + x[2] * sn + a[2] * d * (1 - cs)];
    }
    this.camera.look = norm3(rot(this.camera.look));
    this.camera.up = norm3(rot(this.camera.up));
  };

  // The current positions of a layer (the mean moved along the selected mode, on the model page).
  Viewer.prototype.positions = function (l) {
    var m = this.scene.modes;
    if (!m || !m.displacements || !m.displacements[l.id] || this.mode.w === 0) return l.positions;
    var d = m.displacements[l.id][this.mode.k], w = this.mode.w, p = l.positions;
    var out = new Float32Array(p.length);
    for (var i = 0; i < p.length; i++) out[i] = p[i] + w * d[i];
    return out;
  };

  // The value of the current field at a layer's point `i` or cell `c`.
  Viewer.prototype.values = function (l, p) {
    var f = this.field && this.fieldById[this.field];
    if (!f) return null;
    if (f.id === 'displacement_mode' && this.scene.modes && this.scene.modes.displacements[l.id]) {
      var d = this.scene.modes.displacements[l.id][this.mode.k], w = Math.abs(this.mode.w);
      var n = p.length / 3, v = new Float32Array(n);
      for (var i = 0; i < n; i++) v[i] = w * Math.hypot(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
      return { point: v, field: f };
    }
    if (l.point_values && l.point_values[f.id]) return { point: l.point_values[f.id], field: f };
    if (l.cell_values && l.cell_values[f.id]) return { cell: l.cell_values[f.id], field: f };
    return null;
  };

  Viewer.prototype.update = function () {
    var gl = this.gl, self = this;
    // The mode's displacement: the colour bar ends at its largest for the slider's weight.
    var fm = this.fieldById.displacement_mode, md = this.scene.modes;
    if (fm && md) fm.hi = Math.max(Math.abs(this.mode.w) * (md.max_displacement ? md.max_displacement[this.mode.k] : 1), 1e-12);
    this.buffers.forEach(function (b) { gl.deleteBuffer(b.pos); gl.deleteBuffer(b.nrm); gl.deleteBuffer(b.col); });
    this.buffers = [];
    var axis = this.clip.axis, at = this.lo[axis] + (this.hi[axis] - this.lo[axis]) * this.clip.at;
    this.plane = [axis === 0 ? 1 : 0, axis === 1 ? 1 : 0, axis === 2 ? 1 : 0, at];
    var triangles = 0;
    this.scene.layers.forEach(function (l) {
      if (!l.visible) return;
      var p = self.positions(l), vals = self.values(l, p), maps = self.scene.colormaps;
      var base = l.color || [0.75, 0.75, 0.78];
      var tri = [], tcol = [], edges = [];
      function color(pointIds, cell) {
        if (vals && vals.cell && cell >= 0) return colorOf(maps, vals.field, vals.cell[cell]);
        if (vals && vals.point) {
          var s = 0, n = 0;
          pointIds.forEach(function (i) { var x = vals.point[i]; if (isFinite(x)) { s += x; n++; } });
          return n ? colorOf(maps, vals.field, s / n) : [0.6, 0.6, 0.6];
        }
        return base;
      }
      function pointColor(i) {
        if (vals && vals.point) return colorOf(maps, vals.field, vals.point[i]);
        return null;
      }
      function poly(ids, cell) {
        // a polygon (triangle or quadrilateral) as a fan, with its edges
        var flat = color(ids, cell);
        for (var t = 1; t + 1 < ids.length; t++) {
          var a = ids[0], b = ids[t], c = ids[t + 1];
          tri.push(a, b, c);
          [a, b, c].forEach(function (i) { tcol.push(pointColor(i) || flat); });
        }
        if (l.cells) for (var e = 0; e < ids.length; e++) edges.push(ids[e], ids[(e + 1) % ids.length]);
      }
      if (l.triangles) {
        for (var i = 0; i < l.triangles.length; i += 3) poly([l.triangles[i], l.triangles[i + 1], l.triangles[i + 2]], -1);
      } else if (l.segments) {
        // an outline: its segments, coloured by the field at their points
        var ids = Array.prototype.slice.call(l.segments);
        self.buffers.push(self.lines(p, ids, function (i) { return pointColor(i) || base; }, false, 1));
        return;
      } else if (l.cells) {
        var keep = null;
        if (self.clip.on) {
          var n = l.centroids.length / 3, pl = self.plane;
          keep = new Uint8Array(n);
          for (var c = 0; c < n; c++) {
            keep[c] = pl[0] * l.centroids[3 * c] + pl[1] * l.centroids[3 * c + 1] + pl[2] * l.centroids[3 * c + 2] <= pl[3] ? 1 : 0;
          }
        }
        // Every face Rust paired with its one or two cells: drawn where exactly one of them is
        // kept (the boundary, and the faces between kept and removed cells).
        var C = l.cells, planar = self.scene.dimension !== 3, nf = C.faces.length, slot = 0;
        for (var f = 0; f < C.face_slot_steps.length; f++) {
          slot += C.face_slot_steps[f];
          var c0 = Math.floor(slot / nf), step = C.face_other_steps[f], c1 = c0 + step;
          var a0 = keep ? keep[c0] : 1, a1 = step ? (keep ? keep[c1] : 1) : 0;
          if (planar) {
            if (!a0) continue;
          } else if (a0 + a1 !== 1) {
            continue;
          }
          var local = C.faces[slot % nf], k0 = C.nodes_per_cell;
          poly(local.map(function (j) { return C.nodes[c0 * k0 + j]; }), a0 ? c0 : c1);
        }
      }
      var b = self.upload(p, tri, tcol, l.opacity == null ? 1 : l.opacity, !!l.cells && self.clip.on);
      triangles += tri.length / 3;
      self.buffers.push(b);
      if (edges.length) self.buffers.push(self.lines(p, edges, [0.15, 0.15, 0.15], false));
      if (self.worst && l.worst && l.worst.length && l.cells) {
        var we = [], W = l.cells, k = W.nodes_per_cell;
        l.worst.forEach(function (c) {
          W.faces.forEach(function (face) {
            for (var e = 0; e < face.length; e++) we.push(W.nodes[c * k + face[e]], W.nodes[c * k + face[(e + 1) % face.length]]);
          });
        });
        self.buffers.push(self.lines(p, we, [1, 0, 1], true));
      }
    });
    this.triangles = triangles;
    this.root.setAttribute('data-triangles', String(triangles));
    this.showLegend();
    this.draw();
  };

  Viewer.prototype.upload = function (p, tri, tcol, alpha, clipped) {
    var gl = this.gl, n = tri.length;
    var pos = new Float32Array(n * 3), nrm = new Float32Array(n * 3), col = new Float32Array(n * 3);
    for (var t = 0; t < n; t += 3) {
      var a = tri[t] * 3, b = tri[t + 1] * 3, c = tri[t + 2] * 3;
      var u = [p[b] - p[a], p[b + 1] - p[a + 1], p[b + 2] - p[a + 2]];
      var v = [p[c] - p[a], p[c + 1] - p[a + 1], p[c + 2] - p[a + 2]];
      var nn = norm3(cross(u, v));
      for (var j = 0; j < 3; j++) {
        var q = tri[t + j] * 3, o = (t + j) * 3, cc = tcol[t + j];
        pos[o] = p[q]; pos[o + 1] = p[q + 1]; pos[o + 2] = p[q + 2];
        nrm[o] = nn[0]; nrm[o + 1] = nn[1]; nrm[o + 2] = nn[2];
        col[o] = cc[0]; col[o + 1] = cc[1]; col[o + 2] = cc[2];
      }
    }
    return { mode: gl.TRIANGLES, count: n, pos: this.buffer(pos), nrm: this.buffer(nrm), col: this.buffer(col), alpha: alpha, lit: 1, clip: !clipped, over: false };
  };

  // Lines between the pairs of points `ids`, of colour `rgb` (or `rgb(i)` per point), over
  // everything when `over`; `alpha` defaults to a faint 0.35 (element edges).
  Viewer.prototype.lines = function (p, ids, rgb, over, alpha) {
    var n = ids.length, pos = new Float32Array(n * 3), col = new Float32Array(n * 3);
    for (var i = 0; i < n; i++) {
      var c = typeof rgb === 'function' ? rgb(ids[i]) : rgb;
      for (var d = 0; d < 3; d++) { pos[3 * i + d] = p[ids[i] * 3 + d]; col[3 * i + d] = c[d]; }
    }
    var a = alpha || (over ? 1 : 0.35);
    return { mode: this.gl.LINES, count: n, pos: this.buffer(pos), nrm: this.buffer(new Float32Array(n * 3)), col: this.buffer(col), alpha: a, lit: 0, clip: !over && alpha === 1, over: over };
  };

  Viewer.prototype.buffer = function (data) {
    var gl = this.gl, b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
    return b;
  };

  Viewer.prototype.draw = function () {
    var gl = this.gl, cam = this.camera, c = this.canvas;
    var eye = [cam.target[0] - cam.look[0] * cam.dist, cam.target[1] - cam.look[1] * cam.dist, cam.target[2] - cam.look[2] * cam.dist];
    var z = [-cam.look[0], -cam.look[1], -cam.look[2]], x = norm3(cross(cam.up, z)), y = cross(z, x);
    var view = [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
      -(x[0] * eye[0] + x[1] * eye[1] + x[2] * eye[2]), -(y[0] * eye[0] + y[1] * eye[1] + y[2] * eye[2]), -(z[0] * eye[0] + z[1] * eye[1] + z[2] * eye[2]), 1];
    var near = Math.max(cam.dist - 2 * this.radius, cam.dist * 0.01), far = cam.dist + 2 * this.radius;
    var mvp = mul(perspective(Math.PI / 6, c.width / c.height, near, far), view);
    gl.viewport(0, 0, c.width, c.height);
    gl.clearColor(1, 1, 1, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    // Faces a little behind their edges, so that the edges show.
    gl.enable(gl.POLYGON_OFFSET_FILL);
    gl.polygonOffset(1, 1);
    gl.useProgram(this.prog);
    gl.uniformMatrix4fv(this.loc.mvp, false, new Float32Array(mvp));
    gl.uniform3f(this.loc.eye, eye[0], eye[1], eye[2]);
    gl.uniform4f(this.loc.clip, this.plane[0], this.plane[1], this.plane[2], this.plane[3]);
    var self = this;
    var order = this.buffers.filter(function (b) { return b.alpha >= 1 && !b.over; })
      .concat(this.buffers.filter(function (b) { return b.alpha < 1 && !b.over; }))
      .concat(this.buffers.filter(function (b) { return b.over; }));
    order.forEach(function (b) {
      if (!b.count) return;
      gl.uniform1f(self.loc.clipOn, b.clip && self.clip.on ? 1 : 0);
      gl.uniform1f(self.loc.lit, b.lit);
      gl.uniform1f(self.loc.alpha, b.alpha);
      if (b.alpha < 1) {
        gl.enable(gl.BLEND);
        gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
        gl.depthMask(false);
      } else {
        gl.disable(gl.BLEND);
        gl.depthMask(true);
      }
      if (b.over) gl.disable(gl.DEPTH_TEST); else gl.enable(gl.DEPTH_TEST);
      [['pos', b.pos], ['nrm', b.nrm], ['col', b.col]].forEach(function (a) {
        gl.bindBuffer(gl.ARRAY_BUFFER, a[1]);
        gl.enableVertexAttribArray(self.loc[a[0]]);
        gl.vertexAttribPointer(self.loc[a[0]], 3, gl.FLOAT, false, 0, 0);
      });
      gl.drawArrays(b.mode, 0, b.count);
    });
    gl.depthMask(true);
    if (!this.counted) {
      this.counted = true;
      var px = new Uint8Array(c.width * c.height * 4);
      gl.readPixels(0, 0, c.width, c.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
      var drawn = 0;
      for (var i = 0; i < px.length; i += 4) if (px[i] < 250 || px[i + 1] < 250 || px[i + 2] < 250) drawn++;
      this.root.setAttribute('data-drawn-pixels', String(drawn));
      this.root.setAttribute('data-ready-ms', String(Math.round(performance.now())));
      this.root.setAttribute('data-state', 'drawn');
    }
  };

  Viewer.prototype.showLegend = function () {
    var f = this.field && this.fieldById[this.field];
    this.legend.textContent = '';
    if (!f) return;
    var lo = f.lo, hi = f.hi, maps = this.scene.colormaps;
    var stops = [];
    for (var i = 0; i <= 10; i++) {
      var c = colorOf(maps, f, lo + (hi - lo) * i / 10);
      stops.push('rgb(' + Math.round(c[0] * 255) + ',' + Math.round(c[1] * 255) + ',' + Math.round(c[2] * 255) + ') ' + (i * 10) + '%');
    }
    var unit = f.unit ? ' ' + f.unit : '';
    var bar = el('div', { class: 'am-bar' });
    bar.style.background = 'linear-gradient(to right,' + stops.join(',') + ')';
    this.legend.appendChild(bar);
    this.legend.appendChild(el('span', {}, [fmt(lo) + unit]));
    this.legend.appendChild(el('span', { style: 'float:right' }, [fmt(hi) + unit]));
    this.legend.appendChild(el('div', { class: 'am-caption' }, [f.label]));
  };

  function fmt(v) {
    if (!isFinite(v)) return '–';
    var a = Math.abs(v);
    return a >= 100 ? v.toFixed(0) : a >= 1 ? v.toFixed(2) : v.toPrecision(2);
  }

  // Centres the view on a point (a worst element's row, clicked).
  Viewer.prototype.focus = function (p) {
    this.camera.target = p.slice();
    this.camera.dist = Math.max(this.radius * 0.8, 1e-9);
    this.draw();
  };

  /** The viewer of each container. @type {WeakMap<Element, any>} */
  var VIEWERS = new WeakMap();

  function start() {
    var viewers = /** @type {NodeListOf<HTMLElement>} */ (document.querySelectorAll('div.am-viewer'));
    var pending = viewers.length;
    document.body.setAttribute('data-viewers', String(viewers.length));
    viewers.forEach(function (root) {
      var src = document.getElementById(root.getAttribute('data-scene'));
      function done(state) {
        if (state) root.setAttribute('data-state', state);
        pending--;
        if (pending === 0) document.body.setAttribute('data-viewers-ready', 'yes');
      }
      if (!src) { done('error: no scene'); return; }
      if (typeof DecompressionStream === 'undefined') {
        root.textContent = 'This browser cannot show the 3D view (no DecompressionStream); the pictures below show the same.';
        done('no-decompression');
        return;
      }
      decode(JSON.parse(src.textContent)).then(function (scene) {
        try {
          VIEWERS.set(root, new Viewer(root, /** @type {Scene} */ (scene)));
          done();
        } catch (e) {
          if (String(e.message) === 'no-webgl') {
            root.textContent = 'WebGL is not available in this browser; the pictures below show the same.';
            done('no-webgl');
          } else {
            done('error: ' + e.message);
            throw e;
          }
        }
      }, function (e) { done('error: ' + e); throw e; });
    });
    document.querySelectorAll('[data-focus]').forEach(function (row) {
      row.addEventListener('click', function () {
        var v = VIEWERS.get(document.querySelector('div.am-viewer'));
        if (v) v.focus(row.getAttribute('data-focus').split(',').map(Number));
      });
    });
  }
  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start); else start();
})();
