// The page's data: a JSON manifest (ids, names, shapes, the table of buffers) and one binary
// blob (base64 in a <script> tag) holding every array. vpm view writes both
// (host/collective/view_page.cpp); the layout is documented in docs/view.md.

const TYPES = {
  f32: Float32Array, u32: Uint32Array, i32: Int32Array, i16: Int16Array,
  u16: Uint16Array, u8: Uint8Array, i8: Int8Array,
};

function decodeBase64(text) {
  // the built-in decoder (Chromium 140+, Firefox 133+, Safari 18.2+) skips the whitespace itself
  // and took 60 ms where atob and the copy loop took 210 ms for 60 MB (headless Chromium 156)
  if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text).buffer;
  const bin = atob(text.trim());
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

/** Reads the manifest and the blob from the page; returns {manifest, array(name)}. */
export function loadPageData(doc = document) {
  const manifest = JSON.parse(doc.getElementById('vpm-manifest').textContent);
  if (manifest.format !== 'vpm-view-1') throw new Error(`unknown data format ${manifest.format}`);
  const blob = decodeBase64(doc.getElementById('vpm-buffers').textContent);
  const cache = new Map();
  function array(name) {
    if (cache.has(name)) return cache.get(name);
    const b = manifest.buffers[name];
    if (!b) throw new Error(`the page has no buffer '${name}'`);
    if (b.type === 'q16') {  // 16-bit codes: base + step * code, 65535 = NaN (view_page.cpp)
      if (b.offset % 2) throw new Error(`buffer '${name}' is misaligned`);
      const code = new Uint16Array(blob, b.offset, b.length), a = new Float32Array(b.length);
      for (let i = 0; i < b.length; ++i) a[i] = code[i] === 65535 ? NaN : b.base + b.step * code[i];
      cache.set(name, a);
      return a;
    }
    const Type = TYPES[b.type];
    if (!Type) throw new Error(`buffer '${name}': unknown type ${b.type}`);
    if (b.offset % Type.BYTES_PER_ELEMENT) throw new Error(`buffer '${name}' is misaligned`);
    const a = new Type(blob, b.offset, b.length);
    cache.set(name, a);
    return a;
  }
  return { manifest, array, bytes: blob.byteLength };
}
