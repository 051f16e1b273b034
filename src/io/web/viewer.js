// The solidtex viewer: volumes (three draggable slices or a cut-away corner), filled models
// (their surface textured by a baked 3D texture, a cut plane or corner showing the inside, a
// translucent mode) and skins, drawn with WebGL2. `window.solidtex` is what tests drive.
'use strict';
(() => {
  const api = (window.solidtex = {});
  const $ = (id) => document.getElementById(id);
  const say = (text) => ($('status').textContent = text);
  const rad = (d) => (d * Math.PI) / 180;

  // ---- vectors and 4x4 matrices (column-major, as WebGL takes them) ----
  const add = (a, b) => a.map((v, i) => v + b[i]);
  const sub = (a, b) => a.map((v, i) => v - b[i]);
  const scale = (a, s) => a.map((v) => v * s);
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm = (a) => scale(a, 1 / (Math.hypot(a[0], a[1], a[2]) || 1));

  function mul(a, b) {
    const o = new Float32Array(16);
    for (let c = 0; c < 4; c++)
      for (let r = 0; r < 4; r++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
        o[c * 4 + r] = s;
      }
    return o;
  }
  function perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
  }
  function lookAt(eye, target, up) {
    const z = norm(sub(eye, target)), x = norm(cross(up, z)), y = cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
      -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
  }
  // An affine map p -> origin + p * size (per axis), optionally mirroring y and z.
  function boxMatrix(origin, size) {
    return new Float32Array([size[0], 0, 0, 0, 0, size[1], 0, 0, 0, 0, size[2], 0, origin[0], origin[1], origin[2], 1]);
  }
  function apply(m, p) {
    const v = [0, 0, 0, 0];
    for (let r = 0; r < 4; r++) v[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    return v;
  }

  // ---- WebGL ----
  const canvas = $('view');
  const gl = canvas.getContext('webgl2', { antialias: true });
  if (!gl) return fail('This page needs WebGL2, which this browser does not offer.');

  function compile(type, source) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  function program(vs, fs) {
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl.VERTEX_SHADER, '#version 300 es\n' + vs));
    gl.attachShader(p, compile(gl.FRAGMENT_SHADER, '#version 300 es\nprecision highp float;precision highp int;' +
      'precision highp sampler3D;\n' + fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    // Each active uniform's place and setter, by its type.
    const setters = {};
    const ints = [gl.INT, gl.INT_VEC2, gl.INT_VEC3, gl.INT_VEC4, gl.SAMPLER_3D];
    for (let i = 0; i < gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS); i++) {
      const { name, type } = gl.getActiveUniform(p, i), at = gl.getUniformLocation(p, name);
      setters[name] = type === gl.FLOAT_MAT4 ? (v) => gl.uniformMatrix4fv(at, false, v)
        : ints.includes(type) ? (v) => intVector(at, [v].flat())
        : (v) => floatVector(at, [v].flat());
    }
    return {
      use(values) {
        gl.useProgram(p);
        for (const [name, v] of Object.entries(values)) if (setters[name]) setters[name](v);
      },
    };
  }
  const intVector = (at, v) => gl['uniform' + v.length + 'iv'](at, v);
  const floatVector = (at, v) => gl['uniform' + v.length + 'fv'](at, v);

  // Regions in box coordinates (0 to 1 across the grid): a fragment outside [uKeepLo,
  // uKeepHi] or strictly inside (uHoleLo, uHoleHi) is not drawn.
  // uCut = (n, w) also takes away the half-space n.b > w (n = 0: nothing).
  const REGION = `uniform vec3 uKeepLo, uKeepHi, uHoleLo, uHoleHi; uniform vec4 uCut;
    bool away(vec3 b) {
      return any(lessThan(b, uKeepLo)) || any(greaterThan(b, uKeepHi)) ||
        (all(greaterThan(b, uHoleLo)) && all(lessThan(b, uHoleHi))) || dot(uCut.xyz, b) > uCut.w;
    }`;
  const SLAB = program(
    `layout(location=0) in vec3 aBox; uniform mat4 uMVP; out vec3 vBox;
     void main() { vBox = aBox; gl_Position = uMVP * vec4(aBox, 1.0); }`,
    `in vec3 vBox; uniform sampler3D uTex; uniform ivec3 uDims; uniform int uGrey, uInside;
     uniform float uShade; out vec4 colour; ${REGION}
     void main() {
       if (away(vBox)) discard;
       ivec3 v = clamp(ivec3(floor(vBox * vec3(uDims))), ivec3(0), uDims - 1);
       vec4 t = texelFetch(uTex, v, 0);
       if (uInside == 1 && t.a < 0.5) discard;
       colour = vec4((uGrey == 1 ? t.rrr : t.rgb) * uShade, 1.0);
     }`);
  const SURFACE = program(
    `layout(location=0) in vec3 aPos; layout(location=1) in vec3 aNormal; layout(location=2) in vec3 aColour;
     uniform mat4 uVP; out vec3 vPos, vNormal, vColour;
     void main() { vPos = aPos; vNormal = aNormal; vColour = aColour; gl_Position = uVP * vec4(aPos, 1.0); }`,
    `in vec3 vPos, vNormal, vColour; uniform sampler3D uTex; uniform int uTextured;
     uniform vec3 uLo, uSize, uEye; out vec4 colour; ${REGION}
     void main() {
       vec3 b = (vPos - uLo) / uSize;
       if (uTextured == 1 && away(b)) discard;
       vec3 n = normalize(vNormal), e = normalize(uEye - vPos);
       if (dot(n, e) < 0.0) n = -n;
       vec3 c = uTextured == 1 ? texture(uTex, b).rgb : vColour;
       colour = vec4(c * (0.3 + 0.7 * max(dot(n, e), 0.0)), 1.0);
     }`);
  const RAYS = program(
    `layout(location=0) in vec3 aBox; uniform mat4 uMVP; out vec3 vBox;
     void main() { vBox = aBox; gl_Position = uMVP * vec4(aBox, 1.0); }`,
    `in vec3 vBox; uniform sampler3D uTex; uniform vec3 uEyeBox, uSize, uBack; uniform float uOpacity, uStep;
     uniform vec2 uLevels; uniform int uDensity; out vec4 colour; ${REGION}
     void main() {
       vec3 dir = vBox - uEyeBox;
       vec3 inv = 1.0 / dir, t0 = -uEyeBox * inv, t1 = (1.0 - uEyeBox) * inv;
       vec3 near = min(t0, t1), far = max(t0, t1);
       float start = max(max(max(near.x, near.y), near.z), 0.0);
       float end = min(min(far.x, far.y), far.z);
       float worldLength = length(dir * uSize);
       float dt = uStep / worldLength, tenth = 0.1 * max(max(uSize.x, uSize.y), uSize.z);
       vec3 sum = vec3(0.0); float kept = 1.0;
       for (int i = 0; i < 2048; i++) {
         float t = start + (float(i) + 0.5) * dt;
         if (t > end || kept < 0.004) break;
         vec3 b = uEyeBox + dir * t;
         if (away(b)) continue;
         vec4 s = texture(uTex, b);
         float lum = dot(s.rgb, vec3(0.2126, 0.7152, 0.0722));
         float d = uDensity == 1 ? 1.0 - lum : uDensity == 2 ? lum : 1.0;
         d = s.a * clamp((d - uLevels.x) / (uLevels.y - uLevels.x), 0.0, 1.0);
         float a = 1.0 - pow(1.0 - uOpacity, d * uStep / tenth);
         sum += kept * a * s.rgb; kept *= 1.0 - a;
       }
       colour = vec4(sum + kept * uBack, 1.0);
     }`);
  const LINES = program(
    `layout(location=0) in vec3 aBox; uniform mat4 uMVP; void main() { gl_Position = uMVP * vec4(aBox, 1.0); }`,
    `uniform vec3 uColour; out vec4 colour; void main() { colour = vec4(uColour, 1.0); }`);

  // One buffer for the quads and lines drawn each frame.
  const scratch = { vao: gl.createVertexArray(), buffer: gl.createBuffer() };
  gl.bindVertexArray(scratch.vao);
  gl.bindBuffer(gl.ARRAY_BUFFER, scratch.buffer);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
  gl.bindVertexArray(null);
  function drawPoints(points, mode) {
    gl.bindVertexArray(scratch.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, scratch.buffer);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(points), gl.DYNAMIC_DRAW);
    gl.drawArrays(mode, 0, points.length / 3);
    gl.bindVertexArray(null);
  }
  // The quad of box coordinate `axis` = t, spanning [lo, hi] on the other two axes.
  function quad(axis, t, lo = [0, 0, 0], hi = [1, 1, 1]) {
    const [a, b] = [(axis + 1) % 3, (axis + 2) % 3];
    const corner = (u, v) => {
      const p = [0, 0, 0];
      p[axis] = t; p[a] = u ? hi[a] : lo[a]; p[b] = v ? hi[b] : lo[b];
      return p;
    };
    return [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 0), corner(1, 1), corner(0, 1)].flat();
  }
  // A face of the unit box, counter-clockwise seen from outside.
  function outward(axis, t) {
    const q = quad(axis, t);
    if (t > 0) return q;
    const flipped = [];
    for (let i = q.length - 3; i >= 0; i -= 3) flipped.push(q[i], q[i + 1], q[i + 2]);
    return flipped;
  }
  const BOX_EDGES = (() => {
    const out = [];
    for (let axis = 0; axis < 3; axis++)
      for (let i = 0; i < 4; i++) {
        const p = [0, 0, 0], q = [0, 0, 0], [a, b] = [(axis + 1) % 3, (axis + 2) % 3];
        p[a] = q[a] = i & 1; p[b] = q[b] = i >> 1; q[axis] = 1;
        out.push(...p, ...q);
      }
    return out;
  })();

  function texture3d(dims, bytes, grey, linear) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_3D, t);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    const [inner, format] = grey ? [gl.R8, gl.RED] : [gl.RGBA8, gl.RGBA];
    gl.texImage3D(gl.TEXTURE_3D, 0, inner, dims[0], dims[1], dims[2], 0, format, gl.UNSIGNED_BYTE, bytes);
    const filter = linear ? gl.LINEAR : gl.NEAREST;
    gl.texParameteri(gl.TEXTURE_3D, gl.TEXTURE_MIN_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_3D, gl.TEXTURE_MAG_FILTER, filter);
    for (const w of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R]) gl.texParameteri(gl.TEXTURE_3D, w, gl.CLAMP_TO_EDGE);
    return t;
  }

  // ---- data: base64 of zlib, inflated by the browser ----
  async function unpack(text) {
    const packed = await (await fetch('data:application/octet-stream;base64,' + text)).blob();
    const stream = packed.stream().pipeThrough(new DecompressionStream('deflate'));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }
  // A grid's layer as texture bytes: RGBA for three planes (alpha from `alpha`, else 255),
  // the plane itself for one.
  function layerBytes(planes, count, layer, alpha) {
    if (layer.planes.length === 1) return planes.subarray(layer.planes[0] * count, (layer.planes[0] + 1) * count);
    const out = new Uint8Array(count * 4);
    const [r, g, b] = layer.planes.map((p) => planes.subarray(p * count, (p + 1) * count));
    const a = alpha === undefined ? null : planes.subarray(alpha * count, (alpha + 1) * count);
    for (let i = 0; i < count; i++) {
      out[4 * i] = r[i]; out[4 * i + 1] = g[i]; out[4 * i + 2] = b[i]; out[4 * i + 3] = a ? a[i] : 255;
    }
    return out;
  }
  async function mesh(entry) {
    const bytes = await unpack(entry.data);
    const n = entry.vertices, m = entry.triangles;
    const positions = new Float32Array(bytes.buffer.slice(0, 12 * n));
    const indices = new Uint32Array(bytes.buffer.slice(12 * n, 12 * n + 12 * m));
    const colours = new Float32Array(3 * n).fill(1);
    if (entry.coloured) for (let i = 0; i < 3 * n; i++) colours[i] = bytes[12 * n + 12 * m + i] / 255;
    const normals = new Float32Array(3 * n);
    for (let t = 0; t < 3 * m; t += 3) {
      const [i, j, k] = [indices[t], indices[t + 1], indices[t + 2]];
      const p = (v) => [positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]];
      const face = cross(sub(p(j), p(i)), sub(p(k), p(i)));
      for (const v of [i, j, k]) for (let c = 0; c < 3; c++) normals[3 * v + c] += face[c];
    }
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    [positions, normals, colours].forEach((array, slot) => {
      gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
      gl.bufferData(gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(slot);
      gl.vertexAttribPointer(slot, 3, gl.FLOAT, false, 0, 0);
    });
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, gl.createBuffer());
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indices, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let v = 0; v < n; v++)
      for (let c = 0; c < 3; c++) {
        lo[c] = Math.min(lo[c], positions[3 * v + c]);
        hi[c] = Math.max(hi[c], positions[3 * v + c]);
      }
    return { name: entry.name, vao, count: 3 * m, lo, hi };
  }
  function drawMesh(m) {
    gl.bindVertexArray(m.vao);
    gl.drawElements(gl.TRIANGLES, m.count, gl.UNSIGNED_INT, 0);
    gl.bindVertexArray(null);
  }

  // ---- camera ----
  const camera = { yaw: 30, pitch: 20, dist: 3, target: [0, 0, 0], fov: rad(35) };
  let scene = null;
  function eye() {
    const y = rad(camera.yaw), p = rad(camera.pitch);
    return add(camera.target, scale([Math.sin(y) * Math.cos(p), Math.sin(p), Math.cos(y) * Math.cos(p)], camera.dist));
  }
  // The picture's centre sits in the middle of what the panel leaves free: a shift in
  // canvas pixels to the right.
  function shift() {
    const panelBox = $('panel');
    return panelBox.hidden || canvas.clientWidth < 2.2 * panelBox.offsetWidth ? 0 : (panelBox.offsetWidth + 8) / 2;
  }
  function viewProjection(width, height) {
    const r = scene.radius;
    const near = Math.max(camera.dist - 2 * r, camera.dist * 0.01), far = camera.dist + 2 * r;
    const moved = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, (2 * shift()) / canvas.clientWidth, 0, 0, 1]);
    return mul(moved, mul(perspective(camera.fov, width / height, near, far), lookAt(eye(), camera.target, [0, 1, 0])));
  }
  // The whole scene's sphere in the part of the picture the panel leaves free.
  function frame() {
    camera.target = scene.centre.slice();
    const free = Math.max(1, canvas.clientWidth - 2 * shift()) / Math.max(1, canvas.clientHeight);
    const half = Math.min(camera.fov / 2, Math.atan(Math.tan(camera.fov / 2) * free));
    camera.dist = (scene.radius / Math.sin(half)) * 1.02;
  }
  function zoom(factor) {
    const r = scene.radius;
    camera.dist = Math.min(20 * r, Math.max(0.25 * r, camera.dist * factor));
  }
  // The world ray through a canvas point (CSS pixels).
  function ray(x, y) {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    x -= shift();
    const e = eye(), f = norm(sub(camera.target, e)), right = norm(cross(f, [0, 1, 0])), up = cross(right, f);
    const t = Math.tan(camera.fov / 2), sx = ((2 * x) / w - 1) * t * (w / h), sy = (1 - (2 * y) / h) * t;
    return { origin: e, dir: norm(add(f, add(scale(right, sx), scale(up, sy)))) };
  }

  // ---- the cut: slices or planes at voxel centres, a hole facing the camera ----
  // `grid` is {dims, toWorld (box -> world matrix), fromWorld(p) -> box}.
  function sliceT(grid, axis, index) {
    return (index + 0.5) / grid.dims[axis];
  }
  const NO_HOLE = { lo: [3, 3, 3], hi: [4, 4, 4] };
  const NO_CUT = [0, 0, 0, 1];
  // Light on the faces across x, y and z, so the planes of a corner read apart.
  const SHADE = [0.84, 0.93, 1];
  // A hole a quarter voxel smaller: the outer faces overlap the cut faces' edges instead of
  // leaving a crack of background between them.
  function inset(hole, grid) {
    const e = grid.dims.map((d) => 0.25 / d);
    return { lo: hole.lo.map((v, a) => v + e[a]), hi: hole.hi.map((v, a) => v - e[a]) };
  }
  // The corner of the box facing the eye beyond the three slice planes.
  function corner(grid, at) {
    const e = grid.fromWorld(eye()), lo = [], hi = [];
    for (let a = 0; a < 3; a++) {
      const t = sliceT(grid, a, at[a]);
      if (e[a] > t) { lo.push(t); hi.push(2); } else { lo.push(-1); hi.push(t); }
    }
    return { lo, hi };
  }
  // The half-space beyond a plane across `axis`, on the eye's side.
  function halfSpace(grid, axis, index) {
    const e = grid.fromWorld(eye()), t = sliceT(grid, axis, index), lo = [-1, -1, -1], hi = [2, 2, 2];
    if (e[axis] > t) lo[axis] = t; else hi[axis] = t;
    return { lo, hi };
  }
  // The part of slice `axis` that bounds a hole (the whole slice without one).
  function faceOfHole(axis, hole) {
    const lo = [0, 0, 0], hi = [1, 1, 1];
    for (let a = 0; a < 3; a++) if (a !== axis) { lo[a] = Math.max(0, hole.lo[a]); hi[a] = Math.min(1, hole.hi[a]); }
    return { lo, hi };
  }
  function makeGrid(dims, toWorld) {
    const origin = [toWorld[12], toWorld[13], toWorld[14]];
    // toWorld sends each box axis along one world axis: find which, and its scale.
    const column = (a) => [toWorld[4 * a], toWorld[4 * a + 1], toWorld[4 * a + 2]];
    const along = [0, 1, 2].map((a) => column(a).findIndex((v) => v !== 0));
    const fromWorld = (p) => [0, 1, 2].map((a) => (p[along[a]] - origin[along[a]]) / column(a)[along[a]]);
    return { dims, toWorld, fromWorld };
  }
  // Draw slices: each {axis, index, lo, hi, inside}.
  function drawSlabs(mvp, texture, grid, grey, slabs, shade) {
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_3D, texture);
    for (const s of slabs) {
      SLAB.use({ uMVP: mvp, uTex: 0, uDims: grid.dims, uGrey: grey ? 1 : 0, uInside: s.inside ? 1 : 0,
        uShade: shade ? shade[s.axis] : 1, uKeepLo: [-1, -1, -1], uKeepHi: [2, 2, 2], uCut: NO_CUT,
        uHoleLo: (s.hole || NO_HOLE).lo, uHoleHi: (s.hole || NO_HOLE).hi });
      drawPoints(s.points || quad(s.axis, s.t, s.lo, s.hi), gl.TRIANGLES);
    }
  }
  // The box's six faces as slabs around a hole.
  function faces(hole) {
    const out = [];
    for (let axis = 0; axis < 3; axis++) for (const t of [0, 1]) out.push({ axis, t, hole });
    return out;
  }
  // Slab parts that can be dragged: [{axis, t, lo, hi}].
  function pick(grid, handles, x, y) {
    const r = ray(x, y), o = grid.fromWorld(r.origin), far = grid.fromWorld(add(r.origin, r.dir));
    const d = sub(far, o);
    let best = null;
    for (const h of handles) {
      // an axis plane b[axis] = t, or a plane n.b = w
      const [n, w] = h.plane || [[0, 1, 2].map((a) => Number(a === h.axis)), h.t];
      if (Math.abs(dot(n, d)) < 1e-9) continue;
      const s = (w - dot(n, o)) / dot(n, d);
      if (s <= 0 || (best && s >= best.s)) continue;
      const p = add(o, scale(d, s));
      const lo = h.lo || [0, 0, 0], hi = h.hi || [1, 1, 1];
      const within = (a) => (h.plane === undefined && a === h.axis) || (p[a] >= lo[a] - 1e-6 && p[a] <= hi[a] + 1e-6);
      if ([0, 1, 2].every(within)) best = { s, axis: h.axis, p };
    }
    if (best && scene.holds && !scene.holds(best.p)) return null;
    return best && { axis: best.axis, box: best.p };
  }
  // The mouse travel (CSS pixels) that moves a handle one voxel: along its axis as the
  // axis shows on screen; the oblique plane, which faces the camera, one voxel towards it
  // per OBLIQUE_PX pixels up.
  const OBLIQUE_PX = 2;
  function handleStep(grid, hit) {
    return hit.axis === 'o' ? [0, -OBLIQUE_PX] : screenAxis(grid, hit.axis, hit.box);
  }
  // Canvas pixels (CSS) per voxel when moving along box `axis` from box point `p`.
  function screenAxis(grid, axis, p) {
    const vp = viewProjection(canvas.clientWidth, canvas.clientHeight);
    const toScreen = (b) => {
      const c = apply(vp, apply(grid.toWorld, b));
      return [((c[0] / c[3] + 1) / 2) * canvas.clientWidth, ((1 - c[1] / c[3]) / 2) * canvas.clientHeight];
    };
    const q = p.slice();
    q[axis] += 1 / grid.dims[axis];
    return sub(toScreen(q), toScreen(p));
  }

  // ---- scenes ----
  function volumesScene(data, volumes) {
    const state = { which: 0, layer: 0, at: [0, 0, 0], cut: 'slices' };
    const items = volumes.map((v, i) => {
      const dims = v.dims, size = dims.map((d) => d / Math.max(...dims));
      // Box z is the world's up (y), box y points away (-z): the view from the (+x, +y,
      // +z) corner is the contact sheet's cut-away corner.
      const toWorld = new Float32Array([size[0], 0, 0, 0, 0, 0, -size[1], 0, 0, size[2], 0, 0,
        -size[0] / 2, -size[2] / 2, size[1] / 2, 1]);
      const count = dims[0] * dims[1] * dims[2];
      const textures = v.layers.map((l) => texture3d(dims, layerBytes(data[i], count, l), l.planes.length === 1, false));
      return { name: v.name, grid: makeGrid(dims, toWorld), layers: v.layers, textures };
    });
    const current = () => items[state.which];
    const centreAll = () => (state.at = current().grid.dims.map((d) => Math.floor(d / 2)));
    centreAll();
    const slabs = () => {
      const g = current().grid;
      if (state.cut === 'slices') return [0, 1, 2].map((axis) => ({ axis, t: sliceT(g, axis, state.at[axis]) }));
      const hole = corner(g, state.at);
      return [0, 1, 2].map((axis) => ({ axis, t: sliceT(g, axis, state.at[axis]), ...faceOfHole(axis, hole) }));
    };
    const extent = (it) => it.grid.dims.map((d) => d / Math.max(...it.grid.dims));
    return {
      centre: [0, 0, 0],
      get radius() { return Math.hypot(...extent(current())) / 2; },
      view: [135, 30],
      grid: () => current().grid,
      costly: () => false,
      handles: slabs,
      draw(vp) {
        const it = current(), grey = it.layers[state.layer].planes.length === 1, mvp = mul(vp, it.grid.toWorld);
        const tex = it.textures[state.layer];
        if (state.cut === 'corner') drawSlabs(mvp, tex, it.grid, grey, faces(inset(corner(it.grid, state.at), it.grid)), SHADE);
        drawSlabs(mvp, tex, it.grid, grey, slabs(), state.cut === 'corner' ? SHADE : null);
        if (state.cut === 'corner') return;
        LINES.use({ uMVP: mvp, uColour: [0.55, 0.55, 0.6] });
        drawPoints(BOX_EDGES, gl.LINES);
      },
      // Slice `axis` at `index` alone, one pixel per voxel.
      snapshot(axis, index, draw) {
        const it = current(), [a, b] = [[1, 2], [0, 2], [0, 1]][axis];
        return draw([it.grid.dims[a], it.grid.dims[b]], (mvp) =>
          drawSlabs(mvp, it.textures[state.layer], it.grid, it.layers[state.layer].planes.length === 1,
            [{ axis, t: sliceT(it.grid, axis, index) }], null), a, b);
      },
      move(axis, by) {
        state.at[axis] = Math.min(current().grid.dims[axis] - 1, Math.max(0, state.at[axis] + by));
      },
      state: () => ({ volume: current().name, layer: current().layers[state.layer].name, slices: state.at.slice(), cut: state.cut }),
      keys: [['drag a slice', 'move it'], ['c', 'slices / cut-away corner'], ['l', 'next channel']],
      key(k) {
        if (k === 'c') state.cut = state.cut === 'slices' ? 'corner' : 'slices';
        else if (k === 'l') state.layer = (state.layer + 1) % current().layers.length;
        else return false;
        return true;
      },
      controls(panel) {
        if (items.length > 1)
          panel.select('volume', items.map((it) => it.name), () => state.which, (i) => {
            state.which = i; state.layer = 0; centreAll();
          });
        panel.select('channel', () => current().layers.map((l) => l.name), () => state.layer, (i) => (state.layer = i));
        panel.buttons([['slices', 'slices'], ['cut-away', 'corner']], () => state.cut, (v) => (state.cut = v));
        ['x', 'y', 'z'].forEach((name, axis) =>
          panel.range(name, () => current().grid.dims[axis] - 1, () => state.at[axis], (v) => (state.at[axis] = v)));
      },
    };
  }

  // Outside voxels take the colour of inside neighbours (a few voxels deep), so the
  // surface's trilinear lookups at the boundary never blend in black.
  function grow(rgba, dims, rounds) {
    const [w, h, d] = dims, step = [1, w, w * h];
    for (let round = 0; round < rounds; round++) {
      const filled = [];
      for (let z = 0; z < d; z++)
        for (let y = 0; y < h; y++)
          for (let x = 0, i = (z * h + y) * w; x < w; x++, i++) {
            if (rgba[4 * i + 3] !== 0) continue;
            const sum = [0, 0, 0];
            let n = 0;
            const xyz = [x, y, z];
            for (let a = 0; a < 3; a++)
              for (const s of [-1, 1]) {
                const c = xyz[a] + s;
                if (c < 0 || c >= dims[a]) continue;
                const j = i + s * step[a];
                if (rgba[4 * j + 3] === 0) continue;
                for (let k = 0; k < 3; k++) sum[k] += rgba[4 * j + k];
                n++;
              }
            if (n) filled.push(i, ...sum.map((v) => Math.round(v / n)));
          }
      for (let f = 0; f < filled.length; f += 4) {
        const i = filled[f];
        rgba.set([filled[f + 1], filled[f + 2], filled[f + 3], 1], 4 * i);
      }
    }
    // Grown voxels carry alpha 1 (of 255) to stop the next round; the cut tests alpha >= 0.5.
  }

  function modelsScene(grid, bytes, meshes) {
    const dims = grid.dims, size = dims.map((d) => d * grid.step);
    const box = makeGrid(dims, boxMatrix(grid.lo, size));
    const count = dims[0] * dims[1] * dims[2];
    const alpha = grid.channels.indexOf('A');
    const rgba = layerBytes(bytes, count, grid.layers[0], alpha);
    const exact = texture3d(dims, rgba, false, false);
    const inside = (b) => {
      const v = b.map((t, a) => Math.min(dims[a] - 1, Math.max(0, Math.floor(t * dims[a]))));
      return rgba[4 * (v[0] + dims[0] * (v[1] + dims[1] * v[2])) + 3] >= 128;
    };
    grow(rgba, dims, 2);
    const smooth = texture3d(dims, rgba, false, true);
    let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const m of meshes) for (let a = 0; a < 3; a++) { lo[a] = Math.min(lo[a], m.lo[a]); hi[a] = Math.max(hi[a], m.hi[a]); }
    const state = { cut: 'none', axis: 2, at: dims.map((d) => Math.floor(d / 2)), translucent: false,
      opacity: 0.3, density: 0, levels: [0, 1], facing: [0, 0, 1], shift: 0 };
    const hole = () => state.cut === 'corner' ? corner(box, state.at)
      : state.cut === 'plane' ? halfSpace(box, state.axis, state.at[state.axis]) : NO_HOLE;
    // The oblique cut: the plane through the models' centre facing `facing` (a unit world
    // vector), moved `shift` voxels along it; the side it faces is taken away. In box
    // coordinates n.b > w.
    const voxel = grid.step, reach = Math.ceil(Math.hypot(...size) / 2 / voxel);
    const oblique = () => {
      const n = state.facing, w = dot(n, add(centre, scale(n, state.shift * voxel)));
      return [n.map((v, a) => v * size[a]), w - dot(n, grid.lo)];
    };
    const cutPlane = () => (state.cut === 'oblique' ? oblique() : null);
    const obliqueCap = () => {
      const [n, w] = oblique(), points = [];
      for (let i = 0; i < BOX_EDGES.length; i += 6) {
        const p = BOX_EDGES.slice(i, i + 3), q = BOX_EDGES.slice(i + 3, i + 6);
        const f = dot(n, p) - w, g = dot(n, q) - w;
        if ((f < 0) !== (g < 0)) points.push(add(p, scale(sub(q, p), f / (f - g))));
      }
      if (points.length < 3) return [];
      const c = scale(points.reduce(add), 1 / points.length), u = norm(sub(points[0], c)), v = cross(norm(n), u);
      const angle = (p) => Math.atan2(dot(sub(p, c), v), dot(sub(p, c), u));
      points.sort((a, b) => angle(a) - angle(b));
      const fan = points.flatMap((p, i) => [...c, ...p, ...points[(i + 1) % points.length]]);
      return [{ axis: 2, points: fan, inside: true }];
    };
    const caps = () => {
      const h = hole();
      const axes = state.cut === 'corner' ? [0, 1, 2] : state.cut === 'plane' ? [state.axis] : [];
      return axes.map((axis) => ({ axis, t: sliceT(box, axis, state.at[axis]), inside: true, ...faceOfHole(axis, h) }));
    };
    const region = (h) => {
      const plane = cutPlane();
      return { uKeepLo: [-1, -1, -1], uKeepHi: [2, 2, 2], uHoleLo: h.lo, uHoleHi: h.hi,
        uCut: plane ? [...plane[0], plane[1]] : NO_CUT };
    };
    const centre = scale(add(lo, hi), 0.5);
    return {
      centre,
      radius: Math.hypot(...sub(hi, lo)) / 2,
      view: [30, 20],
      grid: () => box,
      costly: () => state.translucent,
      handles: () => (state.cut === 'oblique' ? [{ axis: 'o', plane: oblique() }] : caps()),
      // A cut face is held only where it shows material.
      holds: (b) => inside(b),
      draw(vp) {
        const h = hole();
        gl.activeTexture(gl.TEXTURE0);
        if (state.translucent) {
          gl.bindTexture(gl.TEXTURE_3D, smooth);
          gl.enable(gl.CULL_FACE);
          gl.cullFace(gl.FRONT);
          RAYS.use({ uMVP: mul(vp, box.toWorld), uTex: 0, uEyeBox: box.fromWorld(eye()), uSize: size,
            uBack: BACKGROUND, uOpacity: state.opacity, uStep: Math.max(...size) / Math.max(...dims),
            uLevels: state.levels, uDensity: state.density, ...region(h) });
          drawPoints(faces(NO_HOLE).flatMap((f) => outward(f.axis, f.t)), gl.TRIANGLES);
          gl.disable(gl.CULL_FACE);
          return;
        }
        gl.bindTexture(gl.TEXTURE_3D, smooth);
        SURFACE.use({ uVP: vp, uTex: 0, uTextured: 1, uLo: grid.lo, uSize: size, uEye: eye(), ...region(h) });
        meshes.forEach(drawMesh);
        const cutFaces = state.cut === 'oblique' ? obliqueCap() : caps();
        drawSlabs(mul(vp, box.toWorld), exact, box, false, cutFaces, state.cut === 'corner' ? SHADE : null);
      },
      snapshot(axis, index, draw) {
        const [a, b] = [[1, 2], [0, 2], [0, 1]][axis];
        return draw([dims[a], dims[b]], (mvp) =>
          drawSlabs(mvp, exact, box, false, [{ axis, t: sliceT(box, axis, index), inside: true }], null), a, b);
      },
      move(axis, by) {
        if (axis === 'o') state.shift = Math.min(reach, Math.max(-reach, state.shift + by));
        else state.at[axis] = Math.min(dims[axis] - 1, Math.max(0, state.at[axis] + by));
      },
      state: () => ({ cut: state.cut, axis: 'xyz'[state.axis], slices: state.at.slice(), translucent: state.translucent, dims,
        facing: state.facing.slice(), shift: state.shift }),
      keys: [['c', 'no cut / plane / corner / oblique'], ['x y z', 'the plane\u2019s axis'],
        ['o', 'an oblique cut facing you'], ['drag the cut', 'move it'], ['t', 'translucent']],
      key(k) {
        if (k === 'c') state.cut = { none: 'plane', plane: 'corner', corner: 'oblique', oblique: 'none' }[state.cut];
        else if (k === 'o') { state.facing = norm(sub(eye(), centre)); state.shift = 0; state.cut = 'oblique'; }
        else if ('xyz'.includes(k)) { state.axis = 'xyz'.indexOf(k); if (state.cut === 'none') state.cut = 'plane'; }
        else if (k === 't') state.translucent = !state.translucent;
        else return false;
        return true;
      },
      controls(panel) {
        panel.buttons([['whole', 'none'], ['plane', 'plane'], ['corner', 'corner'], ['oblique', 'oblique']],
          () => state.cut, (v) => (state.cut = v));
        panel.buttons([['x', 0], ['y', 1], ['z', 2]], () => state.axis, (v) => (state.axis = v), () => state.cut === 'plane');
        const cutting = (axis) => () => state.cut === 'corner' || (state.cut === 'plane' && state.axis === axis);
        ['x', 'y', 'z'].forEach((name, axis) =>
          panel.range(name, () => dims[axis] - 1, () => state.at[axis], (v) => (state.at[axis] = v), cutting(axis)));
        panel.range('shift', () => 2 * reach, () => state.shift + reach, (v) => (state.shift = v - reach),
          () => state.cut === 'oblique');
        panel.buttons([['surface', false], ['translucent', true]], () => state.translucent, (v) => (state.translucent = v));
        const seeThrough = () => state.translucent;
        panel.range('opacity', () => 100, () => Math.round(state.opacity * 100),
          (v) => (state.opacity = Math.min(v, 99.99) / 100), seeThrough);
        panel.select('density', ['uniform', 'dark', 'light'], () => state.density, (i) => (state.density = i), seeThrough);
      },
    };
  }

  function skinScene(meshes) {
    const m = meshes[0];
    return {
      centre: scale(add(m.lo, m.hi), 0.5),
      radius: Math.hypot(...sub(m.hi, m.lo)) / 2,
      view: [30, 20],
      grid: () => null,
      costly: () => false,
      handles: () => [],
      draw(vp) {
        SURFACE.use({ uVP: vp, uTextured: 0, uEye: eye() });
        drawMesh(m);
      },
      snapshot: () => null,
      move() {},
      state: () => ({}),
      keys: [],
      key: () => false,
      controls() {},
    };
  }

  // ---- drawing ----
  const BACKGROUND = [24 / 255, 24 / 255, 28 / 255];
  let queued = false;
  function redraw() {
    if (!queued) {
      queued = true;
      requestAnimationFrame(() => { queued = false; render(); });
    }
  }
  // While the view moves, a scene that costs much per pixel (the translucent one) draws at
  // half resolution; a full one follows once it rests.
  let moving = 0, settle = null;
  function moved() {
    moving = performance.now();
    clearTimeout(settle);
    settle = setTimeout(redraw, 250);
  }
  function render() {
    const coarse = scene.costly() && performance.now() - moving < 200;
    const dpr = (window.devicePixelRatio || 1) * (coarse ? 0.5 : 1);
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, w, h);
    gl.clearColor(...BACKGROUND, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    scene.draw(viewProjection(w, h));
    panel.refresh();
  }
  // Draw `body` into a framebuffer of `size` pixels with box axis a across and b down,
  // and read it back as RGB rows from the top.
  function offscreen(size, body, a, b) {
    const [w, h] = size;
    const fb = gl.createFramebuffer(), colour = gl.createRenderbuffer(), depth = gl.createRenderbuffer();
    gl.bindRenderbuffer(gl.RENDERBUFFER, colour);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.RGBA8, w, h);
    gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, w, h);
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.RENDERBUFFER, colour);
    gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
    gl.viewport(0, 0, w, h);
    gl.clearColor(0, 0, 0, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    // Box axis a runs left to right, b top to bottom.
    const m = new Float32Array(16);
    m[4 * a] = 2; m[4 * b + 1] = -2; m[12] = -1; m[13] = 1; m[15] = 1;
    body(m);
    const rgba = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, rgba);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    [fb].forEach((f) => gl.deleteFramebuffer(f));
    [colour, depth].forEach((r) => gl.deleteRenderbuffer(r));
    const rgb = new Uint8Array(w * h * 3);
    for (let y = 0; y < h; y++)
      for (let x = 0; x < w; x++)
        for (let c = 0; c < 3; c++) rgb[(y * w + x) * 3 + c] = rgba[((h - 1 - y) * w + x) * 4 + c];
    redraw();
    return { width: w, height: h, rgb };
  }

  // ---- the panel ----
  const panel = (() => {
    const root = $('controls'), refreshers = [];
    const changed = (set) => (value) => { set(value); redraw(); };
    return {
      select(name, options, get, set, when) {
        const label = document.createElement('label'), select = document.createElement('select');
        label.append(name, select);
        root.append(label);
        const list = () => (typeof options === 'function' ? options() : options);
        select.onchange = () => { changed(set)(select.selectedIndex); select.blur(); };
        refreshers.push(() => {
          label.hidden = when ? !when() : false;
          const names = list();
          if (select.options.length !== names.length || [...select.options].some((o, i) => o.text !== names[i]))
            select.replaceChildren(...names.map((n) => new Option(n)));
          select.selectedIndex = get();
        });
      },
      buttons(choices, get, set, when) {
        const row = document.createElement('div');
        row.className = 'row';
        const made = choices.map(([text, value]) => {
          const b = document.createElement('button');
          b.textContent = text;
          b.onclick = () => { changed(set)(value); b.blur(); };
          row.append(b);
          return [b, value];
        });
        root.append(row);
        refreshers.push(() => {
          row.hidden = when ? !when() : false;
          made.forEach(([b, v]) => b.classList.toggle('on', get() === v));
        });
      },
      range(name, max, get, set, when) {
        const label = document.createElement('label'), input = document.createElement('input'), out = document.createElement('span');
        input.type = 'range';
        input.min = 0;
        label.append(name, input, out);
        root.append(label);
        input.oninput = () => changed(set)(Number(input.value));
        input.onchange = () => input.blur();
        refreshers.push(() => {
          label.hidden = when ? !when() : false;
          input.max = max(); input.value = get(); out.textContent = get();
        });
      },
      refresh: () => refreshers.forEach((r) => r()),
    };
  })();

  // ---- input: drag orbits, shift-drag pans, wheel zooms, a drag on a slice moves it ----
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => {
    canvas.focus();
    canvas.setPointerCapture(e.pointerId);
    const grid = scene.grid();
    const free = e.shiftKey || e.altKey || e.ctrlKey || e.button !== 0;
    const hit = grid && !free ? pick(grid, scene.handles(), e.offsetX, e.offsetY) : null;
    drag = { x: e.offsetX, y: e.offsetY, pan: e.shiftKey || e.button !== 0, hit, moved: 0 };
    if (hit) drag.axisPx = handleStep(grid, hit);
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
    drag.x = e.offsetX; drag.y = e.offsetY;
    if (drag.hit) {
      const s = drag.axisPx, length2 = dot([...s, 0], [...s, 0]);
      if (length2 < 1e-6) return;
      drag.moved += (dx * s[0] + dy * s[1]) / length2;
      const whole = Math.trunc(drag.moved);
      if (whole) { scene.move(drag.hit.axis, whole); drag.moved -= whole; }
    } else if (drag.pan) {
      const e2 = eye(), f = norm(sub(camera.target, e2)), right = norm(cross(f, [0, 1, 0])), up = cross(right, f);
      const perPixel = (2 * camera.dist * Math.tan(camera.fov / 2)) / canvas.clientHeight;
      camera.target = add(camera.target, add(scale(right, -dx * perPixel), scale(up, dy * perPixel)));
    } else {
      camera.yaw -= dx * 0.4;
      camera.pitch = Math.max(-89, Math.min(89, camera.pitch + dy * 0.4));
    }
    moved();
    redraw();
  });
  const release = () => (drag = null);
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    zoom(Math.exp(Math.max(-1, Math.min(1, e.deltaY * 0.001))));
    moved();
    redraw();
  }, { passive: false });
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  window.addEventListener('keydown', (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement || e.ctrlKey || e.metaKey) return;
    const k = e.key.toLowerCase();
    if (k === 'f') frame();
    else if (k === 'h') showPanel($('panel').hidden);
    else if (!scene.key(k)) return;
    redraw();
  });
  window.addEventListener('resize', redraw);
  function showPanel(shown) {
    $('panel').hidden = !shown;
    $('hint').hidden = shown;
  }

  function fail(message) {
    $('fail').hidden = false;
    $('fail').textContent = message;
    say('');
    api.failure = message;
    console.error('solidtex viewer: ' + message);
  }

  // ---- start ----
  api.ready = (async () => {
    const data = JSON.parse($('solidtex-data').textContent);
    document.title = data.title;
    $('title').textContent = data.title;
    const s = data.scene;
    const most = gl.getParameter(gl.MAX_3D_TEXTURE_SIZE);
    const grids = s.kind === 'volumes' ? s.volumes : s.kind === 'models' ? [s.grid] : [];
    const big = grids.find((g) => Math.max(...g.dims) > most);
    if (big) throw new Error(`${big.name} is ${big.dims.join('x')} voxels; this browser's 3D textures stop at ${most}`);
    if (s.kind === 'volumes') scene = volumesScene(await Promise.all(s.volumes.map((v) => unpack(v.data))), s.volumes);
    else if (s.kind === 'models') scene = modelsScene(s.grid, await unpack(s.grid.data), await Promise.all(s.meshes.map(mesh)));
    else scene = skinScene(await Promise.all(s.meshes.map(mesh)));
    const keys = [['drag', 'orbit'], ['shift-drag', 'pan'], ['wheel', 'zoom'], ['f', 'frame'], ...scene.keys,
      ['h', 'hide this panel']];
    $('keys').innerHTML = keys.map(([k, what]) => `<b>${k}</b> ${what}`).join(' \u00b7 ');
    scene.controls(panel);
    [camera.yaw, camera.pitch] = scene.view;
    if (canvas.clientWidth < 700 || canvas.clientHeight < 480) showPanel(false);
    frame();
    render();
    api.firstFrameMs = performance.now();
    say(s.kind === 'models' ? `baked ${s.grid.dims.join('\u00d7')} voxels`
      : s.kind === 'volumes' ? s.volumes.map((v) => `${v.name}: ${v.dims.join('\u00d7')}, ${v.channels.join(' ')}`).join(' \u00b7 ')
      : `${s.meshes[0].vertices} vertices, ${s.meshes[0].triangles} triangles`);
  })().catch((e) => fail(String(e.message || e)));

  // ---- what tests use ----
  Object.assign(api, {
    glError: () => gl.getError(),
    state: () => ({ camera: { ...camera, target: camera.target.slice() }, ...scene.state() }),
    // Slice `axis` (0, 1, 2) at `index` drawn one pixel per voxel; base64 RGB rows.
    snapshot(axis, index) {
      const shot = scene.snapshot(axis, index, offscreen);
      if (!shot) return null;
      let text = '';
      for (let i = 0; i < shot.rgb.length; i += 8192) text += String.fromCharCode(...shot.rgb.subarray(i, i + 8192));
      return { width: shot.width, height: shot.height, rgb: btoa(text) };
    },
    // The canvas after one frame: its mean colour and a checksum.
    picture() {
      render();
      const w = canvas.width, h = canvas.height, px = new Uint8Array(w * h * 4);
      gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
      let sum = 0, hash = 0;
      for (let i = 0; i < px.length; i++) { sum += px[i]; hash = (hash * 31 + px[i]) >>> 0; }
      return { width: w, height: h, mean: sum / px.length, hash };
    },
    // A canvas point (CSS pixels) on the draggable part of slice or cut `axis`, and the
    // screen step (dx, dy) of one voxel along the axis there; or null.
    handlePoint(axis) {
      const grid = scene.grid();
      if (!grid) return null;
      for (let y = 10; y < canvas.clientHeight; y += 7)
        for (let x = 10; x < canvas.clientWidth; x += 7) {
          if (document.elementFromPoint(x, y) !== canvas) continue;
          const hit = pick(grid, scene.handles(), x, y);
          if (hit && hit.axis === axis) {
            const [dx, dy] = handleStep(grid, hit);
            return { x, y, dx, dy };
          }
        }
      return null;
    },
    key: (k) => { scene.key(k); render(); },
    // Frames per second over `n` frames, each finished before the next.
    framesPerSecond(n) {
      const px = new Uint8Array(4), start = performance.now();
      for (let i = 0; i < n; i++) {
        camera.yaw += 1;
        render();
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
      }
      return (1000 * n) / (performance.now() - start);
    },
  });
})();
