// The live view in a real browser, for crates/trol-cli/tests/view.rs.
//
//   node view.mjs URL SCREENSHOT.png
//
// Opens URL in headless Chromium (Debian's, $CHROMIUM or /usr/bin/chromium) through
// Playwright, waits until the page has shown the arm standing still, saves a screenshot and
// prints
//   shown {"webgl": "ok", "joints": [6 rad as the page shows them], "frames": N}
// Then, for each line `watch` on standard input, it prints `watching`, waits until the page
// has shown the arm moving and then still again (the test moves it meanwhile), and prints
//   followed {"moving_frames": N, "joints": [...], "trail": N, "trail_before": N}
// (the trail's points after the motion, and before it).
// For a line `held` it waits until the page shows an object in the gripper and prints
//   held {"off_mm": centre to the fingers' point, "finger_low_mm": above the table}
// `warnings` prints what the page logged as warnings or errors: `warnings [...]`.
// Every wait is bounded; a failure prints `error ...` and exits with 1.
import { chromium } from 'playwright-core';
import { createInterface } from 'node:readline';

const [url, shot] = process.argv.slice(2);
if (!url || !shot) {
  console.error('usage: node view.mjs URL SCREENSHOT.png');
  process.exit(2);
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  // WebGL in software on a machine without a GPU: this Chromium gives SwiftShader to a page
  // only with both flags.
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox'],
  timeout: 60_000,
});

async function joints(page) {
  return page.evaluate(() =>
    [1, 2, 3, 4, 5, 6].map(i => Number(document.getElementById(`j${i}`).dataset.rad)));
}

try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 650 } });
  page.on('pageerror', e => console.error(`page error: ${e}`));
  const logged = [];
  page.on('console', m => { if (m.type() === 'warning' || m.type() === 'error') logged.push(m.text()); });
  await page.goto(url, { timeout: 30_000 });
  // The first state has arrived and the arm stands.
  await page.waitForFunction(
    () => Number(document.body.dataset.frames || 0) >= 1 && document.body.dataset.moving === 'false',
    null, { timeout: 30_000 });
  // Two animation frames, so the canvas shows that state.
  await page.evaluate(() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r))));
  await page.screenshot({ path: shot, timeout: 30_000 });
  const body = await page.evaluate(() => ({ ...document.body.dataset }));
  // What a person reads: the tool's pose and each joint in degrees.
  const texts = await page.evaluate(() => ({
    tcp: document.getElementById('tcp').textContent,
    joints: [1, 2, 3, 4, 5, 6].map(i => document.getElementById(`j${i}`).textContent),
  }));
  console.log(`shown ${JSON.stringify({ webgl: body.webgl, joints: await joints(page), frames: Number(body.frames) })}`);
  console.log(`texts ${JSON.stringify(texts)}`);

  for await (const line of createInterface({ input: process.stdin })) {
    if (line.trim() === 'warnings') {
      console.log(`warnings ${JSON.stringify(logged)}`);
      continue;
    }
    if (line.trim() === 'held') {
      await page.waitForFunction(
        () => document.body.dataset.held === 'true' && document.body.dataset.moving === 'false',
        null, { timeout: 60_000 });
      await page.evaluate(() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r))));
      const b = await page.evaluate(() => ({ ...document.body.dataset }));
      // What a person sees of the held cube: pixels of its outline's colour within 40 px
      // of where it is on the canvas.
      const outline = await page.evaluate(([x, y]) => {
        const gl = document.querySelector('#scene canvas');
        const c = document.createElement('canvas');
        c.width = 81; c.height = 81;
        const g = c.getContext('2d');
        g.drawImage(gl, x - 40, y - 40, 81, 81, 0, 0, 81, 81);
        const d = g.getImageData(0, 0, 81, 81).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) {
          if (d[i] > 200 && d[i + 1] < 60 && d[i + 2] > 120) n += 1;
        }
        return n;
      }, (b.heldScreen || '0,0').split(',').map(Number));
      console.log(`held ${JSON.stringify({ off_mm: Number(b.heldOffMm), finger_low_mm: Number(b.fingerLowMm), label: b.heldLabel, outline_px: outline })}`);
      continue;
    }
    if (line.trim() !== 'watch') continue;
    // Count the updates that say "moving"; done once one said so and the page is still again.
    const trailBefore = await page.evaluate(() => Number(document.body.dataset.trail || 0));
    await page.evaluate(() => {
      const w = { saw: false, frames: 0 };
      window.__watch = w;
      new MutationObserver(() => {
        if (document.body.dataset.moving === 'true') { w.saw = true; w.frames += 1; }
      }).observe(document.body, { attributes: true, attributeFilter: ['data-frames'] });
    });
    console.log('watching');
    await page.waitForFunction(
      () => window.__watch.saw && document.body.dataset.moving === 'false', null, { timeout: 60_000 });
    const frames = await page.evaluate(() => window.__watch.frames);
    const trail = await page.evaluate(() => Number(document.body.dataset.trail || 0));
    console.log(`followed ${JSON.stringify({ moving_frames: frames, joints: await joints(page), trail, trail_before: trailBefore })}`);
  }
} catch (e) {
  console.log(`error ${String(e).split('\n')[0]}`);
  process.exitCode = 1;
} finally {
  await browser.close();
}
