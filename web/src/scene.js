// One WebGL context for the whole page: every cell of the table (and the detail view) is a
// rectangle of one fixed canvas over the visible cells, drawn with a scissored viewport (browsers
// allow only ~16 contexts). One shared view turns every cell; a row may hold its own view (a
// patient facing its strongest focus), which turns by the same drags, so turning stays coordinated.
import {
  BufferAttribute, BufferGeometry, Color, ColorManagement, LinearSRGBColorSpace, Mesh,
  PerspectiveCamera, Raycaster, Scene, ShaderMaterial, Vector2, Vector3, WebGLRenderer,
} from 'three';

export const CELL_BACKGROUND = new Color(0.06, 0.07, 0.09);

/** Per-vertex colours lit per vertex (a light from the viewer's upper left, a sky/ground
 *  ambient): the fragment shader only passes the colour on, the least work per pixel for
 *  software WebGL (docs/view.md). */
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

/** A view direction: brains in RAS millimetres, superior up; the default from the front left. */
export const defaultView = () => ({ yaw: 4.2, pitch: 0.25 });

/** The view looking at the origin from direction d (x, y, z). */
export function viewFrom(d) {
  const l = Math.hypot(d[0], d[1], d[2]);
  if (!(l > 0)) return defaultView();
  return { yaw: Math.atan2(d[0], -d[1]), pitch: Math.max(-1.5, Math.min(1.5, Math.asin(d[2] / l))) };
}

export class TableScene {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new WebGLRenderer({ canvas, antialias: false, alpha: true });
    this.ratio = 1;
    this.renderer.setPixelRatio(1);
    // colours are used as given (no sRGB conversion), so a pixel's value is predictable in tests
    ColorManagement.enabled = false;
    this.renderer.outputColorSpace = LinearSRGBColorSpace;
    this.renderer.setClearColor(0x000000, 0);
    this.renderer.autoClear = false;
    this.lod = true;          // element-level surfaces while turning
    this.movingScale = 0.5;   // canvas resolution while turning (software WebGL pays per pixel)
    this.moving = false;
    this.scene = new Scene();
    this.camera = new PerspectiveCamera(30, 1, 0.1, 100);
    this.distance = 4.2;      // camera distance at zoom 1 (native brains; 4.0 for the ball)
    this.zoom = 1;
    this.scene.add(this.camera);
    this.material = shadedColours();
    this.mesh = new Mesh(new BufferGeometry(), this.material);
    this.mesh.frustumCulled = false;
    this.scene.add(this.mesh);
    this.raycaster = new Raycaster();
    this.shared = defaultView();
    this.own = new Set();     // rows' own views, turned with the shared one
  }

  /** The view of a cell: its row's own, else the shared one. */
  viewOf(cell) { return cell.row?.view || this.shared; }

  /** Places the camera for `view` and a cell of the given aspect ratio. */
  setCamera(view, aspect) {
    const cp = Math.cos(view.pitch), sp = Math.sin(view.pitch), c = this.camera;
    c.position.set(Math.sin(view.yaw) * cp, -Math.cos(view.yaw) * cp, sp).multiplyScalar(this.distance / this.zoom);
    c.up.set(0, 0, 1);
    c.lookAt(0, 0, 0);
    c.aspect = aspect;
    c.updateProjectionMatrix();
    c.updateMatrixWorld();
  }

  /** Turns every view by a drag of (dx, dy) pixels. While it turns, cells draw their
   *  element-level surface at a lower resolution; 150 ms after the last turn, in full again. */
  rotate(dx, dy) {
    for (const v of [this.shared, ...this.own]) {
      v.yaw -= dx * 0.01;
      v.pitch = Math.max(-1.5, Math.min(1.5, v.pitch + dy * 0.01));
    }
    this.moved();
  }

  /** Zooms every cell by `factor` (within 0.5x .. 4x). */
  zoomBy(factor) {
    this.zoom = Math.max(0.5, Math.min(4, this.zoom * factor));
    this.moved();
  }

  moved() {
    this.moving = true;
    clearTimeout(this.rest);
    this.rest = setTimeout(() => {
      this.moving = false;
      if (this.onRest) this.onRest();
    }, 150);
  }

  /** The element-level geometry over a cell geometry's attributes (the coarse index). */
  coarseOf(g) {
    if (!this.coarseIndex) return g;
    const c = new BufferGeometry();
    c.setIndex(this.coarseIndex);
    for (const name of ['position', 'normal', 'color']) c.setAttribute(name, g.attributes[name]);
    return c;
  }

  /** Which of `cells` are on screen: each with its rectangle and the part of it inside its clip
   *  (the scrolling table or the detail panel) and below its sticky header (`clipTop`). */
  visible(cells) {
    const out = [];
    const rects = new Map();
    const rectOf = (el) => {
      if (!rects.has(el)) rects.set(el, el.getBoundingClientRect());
      return rects.get(el);
    };
    for (const cell of cells) {
      if (cell.hidden) continue;
      const rect = cell.el.getBoundingClientRect();
      const c = rectOf(cell.clip);
      const top = Math.max(rect.top, c.top, cell.clipTop ? rectOf(cell.clipTop).bottom : -Infinity);
      const left = Math.max(rect.left, c.left), right = Math.min(rect.right, c.right);
      const bottom = Math.min(rect.bottom, c.bottom);
      if (right <= left || bottom <= top || rect.width < 2) continue;
      out.push({ cell, rect, left, right, top, bottom });
    }
    return out;
  }

  /** Places the canvas over the bounding box of the shown cells only: software WebGL pays per
   *  canvas pixel for presenting each frame (docs/view.md). */
  placeCanvas(shown) {
    let l = Infinity, t = Infinity, rr = -Infinity, b = -Infinity;
    for (const v of shown) {
      l = Math.min(l, v.left); t = Math.min(t, v.top); rr = Math.max(rr, v.right); b = Math.max(b, v.bottom);
    }
    if (!shown.length) l = t = rr = b = 0;
    const box = [Math.floor(l), Math.floor(t), Math.max(1, Math.ceil(rr) - Math.floor(l)), Math.max(1, Math.ceil(b) - Math.floor(t))];
    const ratio = this.moving && this.lod ? this.movingScale : 1;
    if (String(box) !== String(this.box) || ratio !== this.ratio) {
      this.box = box;
      this.ratio = ratio;
      Object.assign(this.canvas.style, { left: `${box[0]}px`, top: `${box[1]}px`, width: `${box[2]}px`, height: `${box[3]}px` });
      this.renderer.setPixelRatio(ratio);
      this.renderer.setSize(box[2], box[3], false);
    }
  }

  /** Draws the shown cells (from visible(); each with its geometry); returns how many. */
  draw(shown) {
    this.placeCanvas(shown);
    const r = this.renderer;
    const [X, Y, , H] = this.box;
    r.setScissorTest(false);
    r.setClearColor(0x000000, 0);
    r.clear();
    r.setScissorTest(true);
    for (const { cell, rect, left, right, top, bottom } of shown) {
      r.setViewport(rect.left - X, Y + H - rect.bottom, rect.width, rect.height);
      r.setScissor(left - X, Y + H - bottom, right - left, bottom - top);
      r.setClearColor(CELL_BACKGROUND, 1);
      r.clear();
      this.setCamera(this.viewOf(cell), rect.width / rect.height);
      this.mesh.geometry = this.moving && this.lod ? cell.coarse : cell.geometry;
      r.render(this.scene, this.camera);
    }
    r.setClearColor(0x000000, 0);
    return shown.length;
  }

  /** The drawn triangle of `cell` under the client point (x, y), or -1. */
  pick(cell, x, y) {
    if (!cell.geometry) return -1;
    const rect = cell.el.getBoundingClientRect();
    const ndc = new Vector2(((x - rect.left) / rect.width) * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    this.setCamera(this.viewOf(cell), rect.width / rect.height);
    this.mesh.geometry = cell.geometry;
    cell.geometry.boundingSphere = null;  // the surface may have changed since (shell, mode)
    this.raycaster.setFromCamera(ndc, this.camera);
    const hit = this.raycaster.intersectObject(this.mesh, false)[0];
    return hit ? hit.faceIndex : -1;
  }

  /** Client position of point p (cell coordinates) in `rect` and whether the surface there,
   *  with normal n, faces the viewer. */
  project(cell, rect, p, n) {
    this.setCamera(this.viewOf(cell), rect.width / rect.height);
    const v = new Vector3(...p);
    const toEye = this.camera.position.clone().sub(v);
    v.project(this.camera);
    const normal = new Vector3(...n);
    const cos = toEye.dot(normal) / (toEye.length() * normal.length() || 1);
    return { x: rect.left + ((v.x + 1) / 2) * rect.width, y: rect.top + ((1 - v.y) / 2) * rect.height, facing: cos > 0, cos };
  }

  /** What `cell` shows right now, drawn at full resolution (for tests): pixels differing from the
   *  cell background, green-dominated ones (the highlight), blue-dominated ones (z far below the
   *  normals), red-dominated ones and a checksum. */
  cellPixels(cell, shown) {
    this.moving = false;
    this.draw(shown);
    const v = shown.find((s) => s.cell === cell);
    if (!v) return { covered: 0, green: 0, blue: 0, red: 0, checksum: 0, total: 0 };
    const gl = this.renderer.getContext();
    const w = Math.floor(v.right - v.left), h = Math.floor(v.bottom - v.top);
    const px = new Uint8Array(w * h * 4);
    const [X, Y, , H] = this.box;
    gl.readPixels(Math.ceil(v.left) - X, Y + H - Math.floor(v.bottom), w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const bg = [CELL_BACKGROUND.r, CELL_BACKGROUND.g, CELL_BACKGROUND.b].map((c) => Math.round(c * 255));
    let covered = 0, green = 0, blue = 0, red = 0, checksum = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) > 12) ++covered;
      if (px[i + 1] > 80 && px[i + 1] > 1.5 * Math.max(px[i], px[i + 2])) ++green;
      if (px[i + 2] > 60 && px[i + 2] > 1.6 * Math.max(px[i], px[i + 1])) ++blue;
      if (px[i] > 80 && px[i] > 1.6 * Math.max(px[i + 1], px[i + 2])) ++red;
      checksum = (checksum * 31 + px[i] + 7 * px[i + 1] + 13 * px[i + 2]) % 1000000007;
    }
    return { covered, green, blue, red, checksum, total: w * h };
  }
}

export { BufferAttribute, BufferGeometry };
