// The page's data (format vpm-view-2; written by vpm view, host/collective/view_page.cpp; layout in
// docs/view.md): a JSON manifest and named binary chunks. A chunk is either embedded in the page
// (<script type="application/octet-stream" id="vpm-chunk-NAME">, base64) or a file NAME.js in the
// folder beside the page (manifest.data_dir) that calls vpmChunk(hash, name, base64): a <script>
// element loads from file:// where fetch() does not, so the folder opens from disk too. Chunks
// are read when first needed (the rows on screen), and the least recently used ones are dropped
// above a budget, so the browser holds what is shown, not the whole cohort.

const TYPES = {
  f32: Float32Array, f64: Float64Array, u32: Uint32Array, i32: Int32Array, i16: Int16Array,
  u16: Uint16Array, u8: Uint8Array, i8: Int8Array,
};

/** The manifest in the page. */
export function readManifest(doc = document) {
  const manifest = JSON.parse(doc.getElementById('vpm-manifest').textContent);
  if (manifest.format !== 'vpm-view-2') throw new Error(`unknown data format ${manifest.format}`);
  return manifest;
}

function decodeBase64(text) {
  // the built-in decoder (Chromium 140+, Firefox 133+, Safari 18.2+) skips whitespace itself and
  // took 60 ms where atob and a copy loop took 210 ms for 60 MB (headless Chromium 156)
  if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text).buffer;
  const bin = atob(text.replace(/\s+/g, ''));
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

const domReady = (doc) => doc.readyState !== 'loading' ? Promise.resolve()
  : new Promise((resolve) => doc.addEventListener('DOMContentLoaded', resolve, { once: true }));

export class Store {
  /** `budget`: bytes of droppable chunks (rows, columns, details) held at most. */
  constructor(manifest, { doc = document, budget = 160e6 } = {}) {
    this.m = manifest;
    this.doc = doc;
    this.budget = budget;
    this.chunks = new Map();   // name -> { promise, buffer, used }
    this.arrays = new Map();   // buffer name -> typed array
    this.held = 0;             // bytes of droppable chunks held
    this.loadedBytes = 0;      // every chunk's bytes read so far
    this.waiting = new Map();  // folder: chunk name -> { resolve, reject }
    this.clock = 0;
    this.pending = 0;          // chunks being read
    if (manifest.layout === 'folder') window.vpmChunk = (hash, name, text) => this.arrived(hash, name, text);
  }

  /** Whether chunk `name` is in memory. */
  loaded(name) { return !!this.chunks.get(name)?.buffer; }

  /** Chunk `name` (an ArrayBuffer), read once; later calls share the promise. */
  chunk(name) {
    let c = this.chunks.get(name);
    if (!c) {
      c = { buffer: null, used: 0 };
      ++this.pending;
      const read = this.m.layout === 'folder' ? this.fromFolder(name) : this.embedded(name);
      read.finally(() => --this.pending).catch(() => {});
      c.promise = read.then((buffer) => {
        c.buffer = buffer;
        this.loadedBytes += buffer.byteLength;
        if (name !== 'base') this.held += buffer.byteLength;
        this.trim();
        return buffer;
      });
      c.promise.catch(() => this.chunks.delete(name));  // a later call tries again
      this.chunks.set(name, c);
    }
    c.used = ++this.clock;
    return c.promise;
  }

  /** Every chunk in `names`. */
  need(names) { return Promise.all([...new Set(names)].map((n) => this.chunk(n))); }

  /** An embedded chunk, as soon as the parser is past it (the page's first rows come first, so
   *  the table draws while the rest of a large file is still being read). */
  async embedded(name) {
    const id = `vpm-chunk-${name}`;
    for (;;) {
      await new Promise((resolve) => setTimeout(resolve, 0));  // let the parser and the page go on
      const el = this.doc.getElementById(id);
      if (el && (el.nextSibling || this.doc.readyState !== 'loading')) return decodeBase64(el.textContent);
      if (!el && this.doc.readyState !== 'loading') throw new Error(`the page has no data chunk '${name}'`);
      if (!el || !el.nextSibling) await Promise.race([domReady(this.doc), new Promise((resolve) => setTimeout(resolve, 15))]);
    }
  }

  fromFolder(name) {
    return new Promise((resolve, reject) => {
      const file = `${this.m.data_dir}/${name}.js`;
      const script = this.doc.createElement('script');
      script.src = file;
      script.onerror = () => {
        this.waiting.delete(name);
        script.remove();
        reject(new Error(`${file} could not be read: the folder ${this.m.data_dir}/ belongs beside the page`));
      };
      this.waiting.set(name, { resolve, reject, script });
      this.doc.head.appendChild(script);
    });
  }

  /** Called by a chunk file of the folder, with the hash of its content. */
  arrived(hash, name, text) {
    const w = this.waiting.get(name);
    if (!w) return;
    this.waiting.delete(name);
    w.script.remove();
    if (hash !== this.m.chunks[name]?.hash) {
      w.reject(new Error(`${this.m.data_dir}/${name}.js was written for another page (run vpm view again)`));
      return;
    }
    try {
      w.resolve(decodeBase64(text));
    } catch (e) {
      w.reject(e);
    }
  }

  /** Drops the least recently used droppable chunks (and arrays on them) above the budget. */
  trim() {
    if (this.held <= this.budget) return;
    const old = [...this.chunks.entries()].filter(([n, c]) => n !== 'base' && c.buffer).sort((a, b) => a[1].used - b[1].used);
    for (const [name, c] of old) {
      if (this.held <= 0.75 * this.budget) break;
      if (this.pinned?.(name)) continue;
      this.chunks.delete(name);
      this.held -= c.buffer.byteLength;
      for (const [b, entry] of Object.entries(this.m.buffers)) if (entry.chunk === name) this.arrays.delete(b);
      this.onDrop?.(name);
    }
  }

  /** Buffer `name` as a typed array; its chunk must be loaded. q16 buffers (16-bit codes: value =
   *  base + step * code, 65535 = NaN) come back as Float32Array. */
  array(name) {
    const hit = this.arrays.get(name);
    if (hit) return hit;
    const b = this.m.buffers[name];
    if (!b) throw new Error(`the page has no buffer '${name}'`);
    const c = this.chunks.get(b.chunk);
    if (!c?.buffer) throw new Error(`buffer '${name}': chunk '${b.chunk}' is not loaded`);
    c.used = ++this.clock;
    let a;
    if (b.type === 'q16') {
      a = decodeQ16(new Uint16Array(c.buffer, b.offset, b.length), b.base, b.step);
    } else {
      const Type = TYPES[b.type];
      if (!Type) throw new Error(`buffer '${name}': unknown type ${b.type}`);
      if (b.offset % Type.BYTES_PER_ELEMENT) throw new Error(`buffer '${name}' is misaligned`);
      a = new Type(c.buffer, b.offset, b.length);
    }
    this.arrays.set(name, a);
    return a;
  }

  /** The raw 16-bit codes of a q16 buffer (columns of the normals' values). */
  codes(name) {
    const b = this.m.buffers[name];
    const c = this.chunks.get(b.chunk);
    if (!c?.buffer) throw new Error(`buffer '${name}': chunk '${b.chunk}' is not loaded`);
    return new Uint16Array(c.buffer, b.offset, b.length);
  }
}

export function decodeQ16(code, base, step) {
  const a = new Float32Array(code.length);
  for (let i = 0; i < code.length; ++i) a[i] = code[i] === 65535 ? NaN : base + step * code[i];
  return a;
}
