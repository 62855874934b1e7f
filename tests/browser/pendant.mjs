// The pendant in a real browser, for crates/trol-cli/tests/view.rs.
//
//   node pendant.mjs URL_WITH_TOKEN
//
// Opens the page `trol sim --view --control` printed (with #token=...) in headless Chromium
// through Playwright and drives the arm with the page's own buttons, as a user would:
//   0. at READY a jog along x is refused, and the page says what goes instead;
//   1. joints 3 and 5 by +90 degrees (the tool down in front of the arm), then jog +x 10 mm;
//   2. store the place as p1 (its six values listed), jog away, "move to" p1; a jog in the
//      tool's frame, a turn about the world's z, the Halt button on screen at the panel's
//      end; the gripper closed, gripped to 20 mm and opened;
//   3. a long joint move at 5 %, Halt during it;
//   4. the same page without the token shows no pendant, and a request with a wrong token
//      is refused.
// It prints `pendant shown` once the page shows the pendant, then for each step one line
// `STEP {json}` with what /state said; every wait is bounded; a
// failure prints `error ...` and exits with 1.
import { chromium } from 'playwright-core';

const [url] = process.argv.slice(2);
if (!url || !url.includes('#token=')) {
  console.error('usage: node pendant.mjs URL#token=TOKEN');
  process.exit(2);
}
const base = url.split('#')[0];

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox'],
  timeout: 60_000,
});

async function state() {
  const r = await fetch(`${base}state`);
  return r.json();
}

// Until the arm stands (bounded).
async function still(ms = 60_000) {
  const until = Date.now() + ms;
  await new Promise(r => setTimeout(r, 150));
  for (;;) {
    const s = await state();
    if (!s.moving) return s;
    if (Date.now() > until) throw new Error('the arm did not stop');
    await new Promise(r => setTimeout(r, 50));
  }
}

// Click and wait for the page to show the answer of that click.
async function click(page, selector) {
  if (process.env.PENDANT_DEBUG) console.error(`click ${selector}`);
  const before = await page.evaluate(() => document.body.dataset.pendantCalls || '0');
  await page.click(selector, { timeout: 10_000 });
  await page.waitForFunction(
    b => (document.body.dataset.pendantCalls || '0') !== b, before, { timeout: 10_000 });
  return JSON.parse(await page.evaluate(() => document.body.dataset.pendantResult));
}

try {
  const page = await browser.newPage({ viewport: { width: 1100, height: 800 } });
  page.on('pageerror', e => console.error(`page error: ${e}`));
  await page.goto(url, { timeout: 30_000 });
  await page.waitForFunction(() => document.body.dataset.control === 'true', null, { timeout: 30_000 });
  console.log('pendant shown');

  // 0. At READY (homed, stretched upright) a jog along x is out of reach: the page says
  //    what goes instead.
  await page.fill('#jog-step', '10');
  const atReady = await click(page, '[data-jog="x,1"]');
  const hint = await page.evaluate(() => document.getElementById('hint').textContent);
  console.log(`ready ${JSON.stringify({ answer: atReady, hint })}`);

  // 1. To a pose in front of the arm with the joint buttons, then +x 10 mm.
  await page.fill('#speed', '100');
  await click(page, '#speed-set');
  await page.fill('#joint-step', '90');
  for (const joint of ['3', '5']) {
    await page.selectOption('#joint-num', joint);
    const a = await click(page, '[data-joint="1"]');
    if (!a.ok) throw new Error(`joint ${joint}: ${JSON.stringify(a)}`);
    await still();
  }
  const before = await still();
  await page.fill('#jog-step', '10');
  const jog = await click(page, '[data-jog="x,1"]');
  const after = await still();
  console.log(`jog ${JSON.stringify({ answer: jog, before: before.tcp, after: after.tcp })}`);

  // 2. Store p1, away, back.
  await page.fill('#here-name', 'p1');
  const stored = await click(page, '#here');
  await page.waitForSelector('#locations tr[data-name="p1"]', { timeout: 10_000 });
  await page.fill('#jog-step', '40');
  await click(page, '[data-jog="z,1"]');
  const away = await still();
  const back = await click(page, 'button[data-move="p1"]');
  const there = await still();
  console.log(`store ${JSON.stringify({ stored, back, p1: after.tcp, away: away.tcp, there: there.tcp })}`);
  const row = await page.evaluate(() =>
    document.querySelector('#locations tr[data-name="p1"] td.values').textContent);
  // 2a. A name the controller refuses (T1 is a scratch location of the C500 backend): the
  //     refusal stays on the page once the list has been read again.
  const refreshes = await page.evaluate(() => document.body.dataset.locationRefreshes || '0');
  await page.fill('#here-name', 'T1');
  const badName = await click(page, '#here');
  await page.waitForFunction(
    r => (document.body.dataset.locationRefreshes || '0') !== r, refreshes, { timeout: 10_000 });
  const shownRefusal = await page.evaluate(() => ({
    text: document.getElementById('result').textContent,
    refused: document.getElementById('result').className === 'refused',
  }));
  console.log(`badname ${JSON.stringify({ answer: badName, shown: shownRefusal })}`);

  // 2b. In the tool's frame: +x is along the tool (down, here); a turn about the world's z
  //     through the tip; the Halt button on screen with the panel scrolled to its end.
  await page.selectOption('#jog-frame', 'tool');
  await page.fill('#jog-step', '10');
  const toolBefore = await still();
  const toolJog = await click(page, '[data-jog="x,1"]');
  const toolAfter = await still();
  await page.selectOption('#jog-frame', 'world');
  await page.fill('#turn-step', '10');
  const turn = await click(page, '[data-turn="yaw,1"]');
  const turned = await still();
  const haltOnScreen = await page.evaluate(() => {
    const panel = document.getElementById('panel');
    panel.scrollTop = panel.scrollHeight;
    const r = document.getElementById('halt').getBoundingClientRect();
    return r.top >= 0 && r.bottom <= window.innerHeight && r.height > 0;
  });
  console.log(`frames ${JSON.stringify({ row, toolJog, toolBefore: toolBefore.tcp, toolAfter: toolAfter.tcp, turn, turned: turned.tcp, haltOnScreen })}`);

  // 2c. The gripper: close (nothing between the fingers), grip to 20 mm, open.
  async function fingers(answer) {
    const until = Date.now() + 30_000;
    let last = -1;
    for (;;) {
      await new Promise(r => setTimeout(r, 200));
      const g = (await state()).gripper_mm;
      if (g === last) return { answer, mm: g };
      if (Date.now() > until) throw new Error('the fingers did not stop');
      last = g;
    }
  }
  const closed = await fingers(await click(page, '#grip-close'));
  await page.fill('#grip-mm', '20');
  const gripped = await fingers(await click(page, '#grip-to'));
  const opened = await fingers(await click(page, '#grip-open'));
  console.log(`gripper ${JSON.stringify({ closed, gripped, opened })}`);

  // 3. A long move at 5 %, halted.
  await page.fill('#speed', '5');
  await click(page, '#speed-set');
  await page.selectOption('#joint-num', '1');
  await page.fill('#joint-step', '90');
  const start = (await state()).joints;
  const long = await click(page, '[data-joint="1"]');
  await page.waitForFunction(async () => (await (await fetch('/state')).json()).moving, null, { timeout: 10_000 });
  await new Promise(r => setTimeout(r, 700));
  const halt = await click(page, '#halt');
  const stopped = await still();
  console.log(`halt ${JSON.stringify({ long, halt, start, stopped: stopped.joints })}`);

  // 4. Without the token no pendant; a wrong token is refused.
  const bare = await browser.newPage();
  await bare.goto(base, { timeout: 30_000 });
  await bare.waitForFunction(() => document.body.dataset.control !== undefined, null, { timeout: 30_000 });
  const hidden = await bare.evaluate(() => document.getElementById('pendant').hidden);
  const wrong = await fetch(`${base}control/jog?dx=10&token=wrong`, { method: 'POST' });
  console.log(`refused ${JSON.stringify({ hidden, wrong_status: wrong.status, wrong: await wrong.json() })}`);
  await browser.close();
} catch (e) {
  console.log(`error ${e}`);
  await browser.close();
  process.exit(1);
}
