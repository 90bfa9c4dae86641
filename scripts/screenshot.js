// Screenshot of the rerun web viewer, headless (docs/rerun_demo.png). Not part of the tests.
// Needs Debian chromium and `npm install playwright-core`; serve a recording first:
//   .venv/bin/rerun --serve-web --bind 127.0.0.1 --web-viewer-port 9191 --port 9877 dls.rrd
//   node scripts/screenshot.js "http://127.0.0.1:9191/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A9877%2Fproxy" docs/rerun_demo.png 25000
const { chromium } = require('playwright-core');
(async () => {
  const [url, out, wait] = process.argv.slice(2);
  const browser = await chromium.launch({ executablePath: '/usr/bin/chromium',
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
           '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update', '--disable-sync'] });
  const page = await browser.newPage({ viewport: { width: 1600, height: 1000 } });
  page.on('console', m => { if (m.type() === 'error') console.log('console:', m.text().slice(0, 200)); });
  await page.goto(url);
  await page.waitForTimeout(parseInt(wait || '20000'));
  await page.screenshot({ path: out });
  await browser.close();
})();
