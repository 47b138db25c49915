// One WebGL context for the whole page: every cell of the table (and the detail view) is a
// rectangle of one fixed canvas over the visible cells, drawn with a scissored viewport and one shared
// camera, so rotating in any cell rotates all of them (browsers allow only ~16 contexts).
import {
  BufferAttribute, BufferGeometry, Color, ColorManagement, LinearSRGBColorSpace, Mesh,
  PerspectiveCamera, Raycaster, Scene, ShaderMaterial, Vector2, Vector3, WebGLRenderer,
} from 'three';

export const CELL_BACKGROUND = new Color(0.06, 0.07, 0.09);

/** Per-vertex colours lit per vertex (a light from the viewer's upper left, a sky/ground
 *  ambient): the fragment shader only passes the colour on, the least work per pixel for
 *  software WebGL (frame rates equal to three's per-fragment Lambert within the noise of a
 *  loaded 2-core machine, docs/view.md). */
function shadedColours() {
  return new ShaderMaterial({
    vertexColors: true,
    vertexShader: `
      varying vec3 vShade;
      void main() {
        vec3 n = normalize(normalMatrix * normal);
        vec3 l = normalize(vec3(-0.3, 0.5, 1.0));
        float diffuse = max(dot(n, l), 0.0);
        float sky = 0.5 + 0.5 * n.y;
        vShade = color * (0.35 + 0.25 * sky + 0.6 * diffuse);
        gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
      }`,
    fragmentShader: `
      varying vec3 vShade;
      void main() { gl_FragColor = vec4(vShade, 1.0); }`,
  });
}

export class TableScene {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new WebGLRenderer({ canvas, antialias: false, alpha: true });
    this.renderer.setPixelRatio(1);
    // colours are used as given (no sRGB conversion), so a pixel's value is predictable in tests
    ColorManagement.enabled = false;
    this.renderer.outputColorSpace = LinearSRGBColorSpace;
    this.renderer.setClearColor(0x000000, 0);
    this.renderer.autoClear = false;  // each cell clears its own rectangle once
    this.lod = true;      // element-level surfaces while turning
    this.moving = false;
    this.fullClear = true;
    this.scene = new Scene();
    this.camera = new PerspectiveCamera(30, 1, 0.1, 100);
    this.distance = 4.2;
    this.scene.add(this.camera);
    this.material = shadedColours();
    this.mesh = new Mesh(new BufferGeometry(), this.material);
    this.mesh.frustumCulled = false;
    this.scene.add(this.mesh);
    this.cells = [];
    this.raycaster = new Raycaster();
    // brains in RAS millimetres: superior up, seen from the front left by default
    this.yaw = 4.2;
    this.pitch = 0.25;
    this.placeCamera();
  }

  placeCamera() {
    const cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    this.camera.position.set(Math.sin(this.yaw) * cp, -Math.cos(this.yaw) * cp, sp).multiplyScalar(this.distance);
    this.camera.up.set(0, 0, 1);
    this.camera.lookAt(0, 0, 0);
    this.camera.updateMatrixWorld();
  }

  /** Turns the shared camera to look at the origin from direction d (x, y, z). */
  lookFrom(d) {
    const l = Math.hypot(d[0], d[1], d[2]);
    if (!(l > 0)) return;
    this.yaw = Math.atan2(d[0], -d[1]);
    this.pitch = Math.max(-1.5, Math.min(1.5, Math.asin(d[2] / l)));
    this.placeCamera();
  }

  /** Rotates the shared camera by a drag of (dx, dy) pixels. While it turns, cells draw their
   *  element-level surface (`lod`); 150 ms after the last turn they are drawn in full again. */
  rotate(dx, dy) {
    this.yaw -= dx * 0.01;
    this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + dy * 0.01));
    this.placeCamera();
    this.moving = true;
    clearTimeout(this.rest);
    this.rest = setTimeout(() => {
      this.moving = false;
      if (this.onRest) this.onRest();
    }, 150);
  }

  /** The element-level geometry of a cell's geometry: the same attributes, the coarse index. */
  coarseOf(g) {
    if (!this.coarseIndex) return g;
    const c = new BufferGeometry();
    c.setIndex(this.coarseIndex);
    for (const name of ['position', 'normal', 'color']) c.setAttribute(name, g.attributes[name]);
    return c;
  }

  /** A cell: `el` (the DOM rectangle it draws into), its geometry (position and normal
   *  attributes shared by a subject's cells, the index shared by all, colours (Uint8, one
   *  per corner) of its own) and `clip`, the
   *  element whose rectangle bounds it (the scrolling table or the detail panel). */
  addCell(el, clip, index, position, normal, colours, info) {
    const g = new BufferGeometry();
    g.setIndex(index);
    g.setAttribute('position', position);
    g.setAttribute('normal', normal);
    g.setAttribute('color', new BufferAttribute(colours, 3, true));
    g.boundingSphere = null;
    const cell = { el, clip, geometry: g, coarse: this.coarseOf(g), ...info };
    this.cells.push(cell);
    return cell;
  }

  /** The cells on screen now: each with its rectangle and the part of it inside its clip. */
  visibleCells() {
    const out = [];
    const clipRects = new Map();
    for (const cell of this.cells) {
      if (cell.hidden) continue;
      const rect = cell.el.getBoundingClientRect();
      if (!clipRects.has(cell.clip)) clipRects.set(cell.clip, cell.clip.getBoundingClientRect());
      const c = clipRects.get(cell.clip);
      const left = Math.max(rect.left, c.left), right = Math.min(rect.right, c.right);
      const top = Math.max(rect.top, c.top), bottom = Math.min(rect.bottom, c.bottom);
      if (right <= left || bottom <= top || rect.width < 2) continue;
      out.push({ cell, rect, left, right, top, bottom });
    }
    return out;
  }

  /** Places the canvas over the bounding box of the visible cells only: software WebGL pays per
   *  canvas pixel for presenting each frame, so a canvas no larger than the cells is faster
   *  (docs/view.md). Resized only when the box changes (scrolling, layout). */
  placeCanvas(shown) {
    let l = Infinity, t = Infinity, rr = -Infinity, b = -Infinity;
    for (const v of shown) {
      l = Math.min(l, v.left); t = Math.min(t, v.top); rr = Math.max(rr, v.right); b = Math.max(b, v.bottom);
    }
    if (!shown.length) l = t = rr = b = 0;
    const box = [Math.floor(l), Math.floor(t), Math.max(1, Math.ceil(rr) - Math.floor(l)), Math.max(1, Math.ceil(b) - Math.floor(t))];
    if (String(box) !== String(this.box)) {
      this.box = box;
      Object.assign(this.canvas.style, { left: `${box[0]}px`, top: `${box[1]}px`, width: `${box[2]}px`, height: `${box[3]}px` });
      this.renderer.setSize(box[2], box[3], false);
    }
  }

  /** Draws every cell whose rectangle is on screen; returns how many were drawn. */
  render() {
    const shown = this.visibleCells();
    this.placeCanvas(shown);
    const r = this.renderer;
    const [X, Y, , H] = this.box;
    r.setScissorTest(false);
    if (this.fullClear) r.clear();
    r.setScissorTest(true);
    for (const { cell, rect, left, right, top, bottom } of shown) {
      r.setViewport(rect.left - X, Y + H - rect.bottom, rect.width, rect.height);
      r.setScissor(left - X, Y + H - bottom, right - left, bottom - top);
      r.setClearColor(CELL_BACKGROUND, 1);
      r.clear();
      this.camera.aspect = rect.width / rect.height;
      this.camera.updateProjectionMatrix();
      this.mesh.geometry = this.moving && this.lod ? cell.coarse : cell.geometry;
      r.render(this.scene, this.camera);
    }
    r.setClearColor(0x000000, 0);
    return shown.length;
  }

  /** The display triangle of `cell` under the client point (x, y), or -1. */
  pick(cell, x, y) {
    const rect = cell.el.getBoundingClientRect();
    const ndc = new Vector2(((x - rect.left) / rect.width) * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    this.camera.aspect = rect.width / rect.height;
    this.camera.updateProjectionMatrix();
    this.mesh.geometry = cell.geometry;
    this.raycaster.setFromCamera(ndc, this.camera);
    const hit = this.raycaster.intersectObject(this.mesh, false)[0];
    return hit ? hit.faceIndex : -1;
  }

  /** What `cell` shows right now (drawn just now; for tests): pixels differing from the cell
   *  background, green-dominated pixels (the highlight colour, shaded; the z scale has no
   *  green), blue-dominated ones (z far below the normals) and a checksum. */
  cellPixels(cell) {
    this.render();
    const rect = cell.el.getBoundingClientRect();
    const gl = this.renderer.getContext();
    const w = Math.floor(rect.width), h = Math.floor(rect.height);
    const px = new Uint8Array(w * h * 4);
    const [X, Y, , H] = this.box;
    gl.readPixels(Math.ceil(rect.left) - X, Y + H - Math.floor(rect.bottom), w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const bg = [CELL_BACKGROUND.r, CELL_BACKGROUND.g, CELL_BACKGROUND.b].map((v) => Math.round(v * 255));
    let covered = 0, matching = 0, blue = 0, checksum = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) > 12) ++covered;
      if (px[i + 1] > 80 && px[i + 1] > 1.5 * Math.max(px[i], px[i + 2])) ++matching;
      if (px[i + 2] > 60 && px[i + 2] > 1.6 * Math.max(px[i], px[i + 1])) ++blue;
      checksum = (checksum * 31 + px[i] + 7 * px[i + 1] + 13 * px[i + 2]) % 1000000007;
    }
    return { covered, green: matching, blue, checksum, total: w * h };
  }

  cameraState() {
    const q = this.camera.quaternion;
    return { yaw: this.yaw, pitch: this.pitch, quaternion: [q.x, q.y, q.z, q.w], position: this.camera.position.toArray() };
  }
}

export { BufferAttribute, Vector3 };
