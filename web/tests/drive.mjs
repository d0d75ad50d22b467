// Drives headless Chromium (WebGPU on SwiftShader) to a page with one <oslf-viewer>, waits for
// it to finish streaming (or to show an error), screenshots its canvas and prints what it
// reported as JSON. Used by tests/web.rs of the oslf crate and by docs/measurements.md.
//
//   node drive.mjs URL [--png OUT.png] [--no-webgpu] [--timeout MS] [--first-frame]
//                      [--time-frames N] [--lose-device]
//
// --no-webgpu: the page runs without navigator.gpu (a browser without WebGPU).
// --first-frame: screenshot as soon as the first frame is drawn.
import { chromium } from 'playwright-core';

const args = process.argv.slice(2);
const url = args[0];
const flag = (name) => args.includes(name);
const value = (name, d) => (args.includes(name) ? args[args.indexOf(name) + 1] : d);
const png = value('--png', null);
const timeout = Number(value('--timeout', '240000'));

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  // WebGPU on SwiftShader through Vulkan: without these, the device is destroyed as soon as a
  // frame is drawn to a canvas (Chromium 156, headless).
  args: ['--headless=new', '--no-sandbox', '--enable-unsafe-webgpu', '--enable-features=Vulkan',
    '--use-vulkan=swiftshader', '--use-angle=vulkan',
    '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
let out = {};
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 }, deviceScaleFactor: 1 });
  const console_ = [];
  page.on('console', (m) => console_.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => console_.push(`pageerror: ${e.message}`));
  if (flag('--no-webgpu')) {
    await page.addInitScript(() => Object.defineProperty(Navigator.prototype, 'gpu', { get: () => undefined }));
  }
  const t0 = Date.now();
  await page.goto(url);
  const done = flag('--first-frame') ? 'v.stats.firstFrameMs !== null' : 'v.stats.completeMs !== null';
  let timedOut = false;
  await page.waitForFunction(`(() => { const v = document.querySelector('oslf-viewer'); return v && (v.error || ${done}); })()`,
    null, { timeout, polling: 100 }).catch(() => { timedOut = true; });
  // Let the last frame reach the canvas.
  await page.waitForTimeout(200);
  // --lose-device: the GPU device goes away (destroyed, as a driver reset would); the page
  // must say so.
  if (flag('--lose-device')) {
    await page.evaluate(() => document.querySelector('oslf-viewer').device?.destroy());
    await page.waitForFunction(() => document.querySelector('oslf-viewer').error !== null, null, { timeout: 10000 }).catch(() => {});
  }
  const state = await page.evaluate(() => {
    const v = document.querySelector('oslf-viewer');
    return { steps: v.steps ?? [], stats: v.stats, error: v.error, lastFrame: v.lastFrame ?? null,
      variant: v.variant?.encoding ?? null, slots: v.variant?.slots ?? null,
      message: v.shadowRoot.querySelector('.msg').textContent,
      messageShown: v.shadowRoot.querySelector('.msg').classList.contains('shown') };
  });
  if (png) await page.locator('oslf-viewer canvas').screenshot({ path: png });
  // --time-frames N: N more frames of the same view, each timed from its request to its
  // feedback (the GPU's work done), after the cache is full.
  const frames = Number(value('--time-frames', '0'));
  if (frames > 0 && !state.error) {
    state.frameMs = await page.evaluate(async (n) => {
      const v = document.querySelector('oslf-viewer');
      const times = [];
      for (let i = 0; i < n; i++) {
        const t = performance.now();
        const done = new Promise((r) => v.addEventListener('oslf-frame', r, { once: true }));
        v.schedule();
        await done;
        times.push(performance.now() - t);
      }
      return times;
    }, frames);
  }
  out = { ...state, timedOut, wallMs: Date.now() - t0, console: console_ };
} catch (e) {
  out = { driverError: String(e) };
} finally {
  await browser.close();
}
console.log(JSON.stringify(out));
