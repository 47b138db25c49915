// Shared pieces of the browser tests: checks that count failures (a step that throws fails, the
// others still run), screenshots decoded to RGBA (a minimal PNG reader: 8-bit RGB/RGBA, not
// interlaced, as Chromium writes them) and pixel counts on them.
import zlib from 'node:zlib';

export class Checks {
  constructor() { this.failures = 0; }
  check(ok, what) {
    console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
    if (!ok) this.failures++;
    return ok;
  }
  /** Runs `fn`; an exception is one failure named `what`. */
  async step(what, fn) {
    try {
      await fn();
    } catch (e) {
      this.check(false, `${what}: ${String(e.message || e).split('\n')[0]}`);
    }
  }
  finish() {
    console.log(this.failures ? `${this.failures} check(s) failed` : 'all checks passed');
    process.exit(this.failures ? 1 : 0);
  }
}

/** {width, height, rgba} of a PNG buffer. */
export function decodePng(buf) {
  let pos = 8, width = 0, height = 0, channels = 0;
  const idat = [];
  while (pos < buf.length) {
    const len = buf.readUInt32BE(pos), type = buf.toString('ascii', pos + 4, pos + 8), data = buf.subarray(pos + 8, pos + 8 + len);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      if (data[8] !== 8 || data[12] !== 0) throw new Error('PNG: only 8-bit, non-interlaced');
      channels = { 2: 3, 6: 4 }[data[9]];
      if (!channels) throw new Error(`PNG: colour type ${data[9]}`);
    } else if (type === 'IDAT') {
      idat.push(data);
    }
    pos += 12 + len;
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels, out = new Uint8Array(width * height * 4), prev = new Uint8Array(stride), cur = new Uint8Array(stride);
  for (let y = 0; y < height; ++y) {
    const f = raw[y * (stride + 1)];
    for (let x = 0; x < stride; ++x) {
      const r = raw[y * (stride + 1) + 1 + x], a = x >= channels ? cur[x - channels] : 0, b = prev[x], c = x >= channels ? prev[x - channels] : 0;
      let p = 0;
      if (f === 1) p = a;
      else if (f === 2) p = b;
      else if (f === 3) p = (a + b) >> 1;
      else if (f === 4) {
        const q = a + b - c, pa = Math.abs(q - a), pb = Math.abs(q - b), pc = Math.abs(q - c);
        p = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[x] = (r + p) & 255;
    }
    for (let x = 0; x < width; ++x) {
      for (let k = 0; k < 3; ++k) out[4 * (y * width + x) + k] = cur[channels * x + k];
      out[4 * (y * width + x) + 3] = channels === 4 ? cur[channels * x + 3] : 255;
    }
    prev.set(cur);
  }
  return { width, height, rgba: out };
}

/** Pixels of a screenshot of `rect` (client coordinates) counted by kind: green-dominated (the
 *  highlight and its marker; the colour scales have no green), saturated red or blue (z beyond
 *  the threshold in a focus), the dark cell background; and the green pixels' bounding box. */
export async function shot(page, rect) {
  const clip = { x: Math.max(0, Math.floor(rect.x)), y: Math.max(0, Math.floor(rect.y)), width: Math.floor(rect.width), height: Math.floor(rect.height) };
  const { width, height, rgba } = decodePng(await page.screenshot({ clip }));
  let green = 0, red = 0, blue = 0, dark = 0, gx0 = Infinity, gx1 = -Infinity, gy0 = Infinity, gy1 = -Infinity;
  for (let y = 0; y < height; ++y)
    for (let x = 0; x < width; ++x) {
      const i = 4 * (y * width + x), r = rgba[i], g = rgba[i + 1], b = rgba[i + 2];
      if (g > 120 && g > 1.6 * Math.max(r, b)) {
        ++green;
        gx0 = Math.min(gx0, x); gx1 = Math.max(gx1, x); gy0 = Math.min(gy0, y); gy1 = Math.max(gy1, y);
      }
      if (r > 90 && r > 1.8 * Math.max(g, b)) ++red;
      if (b > 80 && b > 1.7 * Math.max(r, g)) ++blue;
      if (r < 30 && g < 30 && b < 40) ++dark;
    }
  return { green, red, blue, dark, total: width * height, greenBox: green ? [gx1 - gx0 + 1, gy1 - gy0 + 1] : [0, 0] };
}

/** The accessible name of each element matching `selector` that has none (aria-label,
 *  aria-labelledby, a wrapping <label> or text). */
export function unnamed(page, selector) {
  return page.evaluate((sel) => [...document.querySelectorAll(sel)].filter((el) => {
    if (el.closest('[hidden]') || el.getClientRects().length === 0) return false;
    const name = el.getAttribute('aria-label') || (el.getAttribute('aria-labelledby') || '').split(' ').map((id) => document.getElementById(id)?.textContent || '').join('') ||
      el.closest('label')?.textContent || (el.tagName !== 'INPUT' && el.tagName !== 'CANVAS' ? el.textContent : '');
    return !String(name).trim();
  }).map((el) => el.id || `${el.tagName.toLowerCase()}.${el.className}`), selector);
}

/** The page's cells (window.vpmView.cells()) with group and kind filled in where a page's hooks
 *  give only the column's label (pages before issue 37: the tests run on them too, to show what
 *  they catch). */
export async function cellsOf(page) {
  return page.evaluate(() => {
    const v = window.vpmView;
    const group = Object.fromEntries(v.manifest.subjects.map((s) => [s.id, s.group]));
    return v.cells().map((c) => ({ ...c, group: c.group ?? group[c.subject], kind: c.kind ?? (/z-score/.test(c.column) ? 'z' : 'value'),
      feature: c.feature ?? c.column.split(' ')[0] }));
  });
}

/** Waits until every cell on screen is drawn (pages without the hook: a short pause). */
export async function settled(page) {
  await page.evaluate(async () => (window.vpmView.settled ? window.vpmView.settled() : new Promise((r) => setTimeout(r, 200))));
}
