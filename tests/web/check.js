// Opens a `solidtex web` page in Debian's chromium (software WebGL) and reports, as one
// JSON line, what tests/it/web.rs checks: console errors, page errors, gl.getError(), the
// first frame's time, slices drawn one pixel per voxel, what drags and the wheel changed,
// and frames per second.
//
// node check.js PLAN.json, where PLAN is
//   {"page": "/abs/view.html", "keys": ["c"], "snapshots": [[2, 10]], "drag": 2, "fps": 30,
//    "screenshot": "/abs/shot.png"}
// ("drag": the slice or cut axis to drag, or null; "screenshot": the page after the keys and
// the interaction, optional; "report": true when "page" is a library report, whose first 3D
// view is opened and checked).
const fs = require('fs');
const puppeteer = require('puppeteer-core');

const FLAGS = ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run',
  '--disable-quic', '--disable-extensions'];

async function main(plan) {
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: FLAGS,
  });
  try {
    return await check(browser, plan);
  } finally {
    await browser.close();
  }
}

async function check(browser, plan) {
  const page = await browser.newPage();
  await page.setViewport({ width: 800, height: 600 });
  const report = { console_errors: [], page_errors: [] };
  page.on('console', (m) => m.type() === 'error' && report.console_errors.push(m.text()));
  page.on('pageerror', (e) => report.page_errors.push(String(e)));
  await page.goto('file://' + plan.page, { waitUntil: 'load' });
  let viewer = page;
  if (plan.report) {
    // A library report: open the first row's 3D view, then check the page inside it.
    await page.click('details summary');
    viewer = await (await page.waitForSelector('details iframe')).contentFrame();
  }
  await viewer.waitForFunction(() => window.solidtex && (window.solidtex.firstFrameMs || window.solidtex.failure), {
    timeout: 120000,
  });
  const view = (f, ...args) => viewer.evaluate(f, ...args);
  report.failure = await view(() => window.solidtex.failure || null);
  if (report.failure) return report;
  report.first_frame_ms = await view(() => window.solidtex.firstFrameMs);
  report.gl_error = await view(() => window.solidtex.glError());
  for (const k of plan.keys || []) await view((k) => window.solidtex.key(k), k);
  report.picture = await view(() => window.solidtex.picture());
  report.snapshots = [];
  for (const [axis, index] of plan.snapshots || [])
    report.snapshots.push({ axis, index, ...(await view((a, i) => window.solidtex.snapshot(a, i), axis, index)) });
  if (plan.drag !== undefined && plan.drag !== null) report.interaction = await interact(page, view, plan.drag);
  if (plan.screenshot) await page.screenshot({ path: plan.screenshot });
  if (plan.fps) report.fps = await view((n) => window.solidtex.framesPerSecond(n), plan.fps);
  report.gl_error_at_end = await view(() => window.solidtex.glError());
  return report;
}

// Drags slice `axis` five voxels, orbits from the background, zooms with the wheel and pans
// with shift-drag; each step's state and picture.
async function interact(page, view, axis) {
  const look = () => view(() => ({ state: window.solidtex.state(), picture: window.solidtex.picture() }));
  const steps = { start: await look() };
  const handle = await view((a) => window.solidtex.handlePoint(a), axis);
  steps.handle = handle;
  if (handle) {
    const len = Math.hypot(handle.dx, handle.dy);
    const [ux, uy] = [handle.dx / len, handle.dy / len];
    await page.mouse.move(handle.x, handle.y);
    await page.mouse.down();
    for (let k = 1; k <= 5; k++) await page.mouse.move(handle.x + ux * len * k, handle.y + uy * len * k);
    await page.mouse.up();
    steps.slice = await look();
  }
  await page.mouse.move(780, 580);
  await page.mouse.down();
  await page.mouse.move(740, 570, { steps: 4 });
  await page.mouse.up();
  steps.orbit = await look();
  await page.mouse.move(400, 300);
  await page.mouse.wheel({ deltaY: 300 });
  steps.wheel = await look();
  await page.keyboard.down('Shift');
  await page.mouse.move(780, 580);
  await page.mouse.down();
  await page.mouse.move(760, 560, { steps: 3 });
  await page.mouse.up();
  await page.keyboard.up('Shift');
  steps.pan = await look();
  return steps;
}

const plan = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
main(plan)
  .then((report) => console.log(JSON.stringify(report)))
  .catch((e) => {
    console.error(e);
    process.exit(2);
  });
