// Screenshots the <model-viewer> page given (can.html) in headless Chromium with WebGL on
// SwiftShader: `node shoot.mjs URL OUT.png`. docs/measurements.md, "The web viewer against
// <model-viewer>", gives the whole procedure.
import { chromium } from "playwright-core";
const [url, png] = process.argv.slice(2);
const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking'] });
const page = await browser.newPage({ viewport: { width: 400, height: 300 }, deviceScaleFactor: 1 });
page.on('console', (m) => console.log('console:', m.text()));
await page.goto(url);
await page.waitForFunction(() => document.title !== '', null, { timeout: 120000 });
console.log('title', await page.title());
await page.locator('#mv').screenshot({ path: png });
await browser.close();
