// Headless Chromium for the view's tests and benchmark: Debian's chromium driven by
// playwright-core (web/'s npm packages). CHROMIUM overrides the browser's path.
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';
import path from 'node:path';

const here = path.dirname(fileURLToPath(import.meta.url));
const require = createRequire(path.join(here, '..', '..', 'web', 'package.json'));
const { chromium } = require('playwright-core');

/** A browser with WebGL in software (SwiftShader), as on a machine without a GPU. */
export async function launch() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-dev-shm-usage'],
  });
}

/** Opens `page_path` (a file) at the given viewport; collects console errors and page errors.
 *  `init`: a function run in the page before its own scripts (page.addInitScript). */
export async function openPage(browser, pagePath, viewport = { width: 1280, height: 800 }, init = null) {
  const page = await browser.newPage({ viewport });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(e.message));
  if (init) await page.addInitScript(init);
  await page.goto('file://' + path.resolve(pagePath));
  await page.waitForSelector('body[data-ready=true]', { timeout: 60000 });
  return { page, errors };
}
