// The web client in headless Chromium against a real `fovea serve`: the page shows a frame that
// is not blank, and moving the mouse moves the gaze marker the server draws.
//
// FOVEA_BIN names the binary (default: target/release/fovea); CHROMIUM the browser
// (default: /usr/bin/chromium). The screenshot lands in tests/browser/artifacts/.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const root = resolve(here, '..', '..');
const bin = process.env.FOVEA_BIN ?? join(root, 'target', 'release', 'fovea');
const artifacts = join(here, 'artifacts');

let server;
let baseUrl;
let browser;

function startServer() {
  return new Promise((resolveUrl, reject) => {
    const child = spawn(bin, ['serve', '--addr', '127.0.0.1:0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    let stderr = '';
    child.stderr.on('data', (d) => { stderr += d; });
    child.on('error', reject);
    child.on('exit', (code) => reject(new Error(`fovea serve exited with ${code} before listening:\n${stderr}`)));
    let out = '';
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/listening on (http:\/\/\S+?)\/?\s/);
      if (m) resolveUrl({ child, url: m[1] });
    });
    setTimeout(() => reject(new Error(`fovea serve did not start in 60 s:\n${stderr}`)), 60_000).unref();
  });
}

before(async () => {
  ({ child: server, url: baseUrl } = await startServer());
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
});

after(async () => {
  await browser?.close();
  if (server && server.exitCode === null) {
    const exited = new Promise((r) => server.once('exit', (code, signal) => r({ code, signal })));
    server.kill('SIGTERM');
    const { code } = await exited;
    assert.equal(code, 0, 'fovea serve exits cleanly on SIGTERM');
  }
});

// Centroid of the marker's magenta pixels in the canvas, in canvas pixels.
async function markerCentroid(page) {
  return page.evaluate(() => {
    const c = document.getElementById('view');
    const data = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let sx = 0; let sy = 0; let n = 0;
    for (let i = 0; i < data.length; i += 4) {
      if (data[i] > 190 && data[i + 1] < 130 && data[i + 2] > 140) {
        const k = i / 4;
        sx += (k % c.width) + 0.5; sy += Math.floor(k / c.width) + 0.5; n += 1;
      }
    }
    return n === 0 ? null : { x: sx / n, y: sy / n, n, w: c.width, h: c.height };
  });
}

// Moves the mouse to (fx, fy) of the canvas and waits for a frame that used that gaze.
async function gazeAt(page, fx, fy) {
  const box = await page.locator('#view').boundingBox();
  await page.mouse.move(box.x + fx * box.width, box.y + fy * box.height, { steps: 4 });
  await page.waitForFunction(([x, y]) => {
    const h = window.fovea.lastHeader;
    return h && h.seq !== null && Math.abs(h.gaze.x - x) < 0.01 && Math.abs(h.gaze.y - y) < 0.01;
  }, [fx, fy], { timeout: 30_000 });
}

test('the page streams frames and the server-drawn marker follows the mouse', async () => {
  const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  await page.goto(`${baseUrl}/`);
  await page.waitForFunction(() => window.fovea && window.fovea.framesShown >= 1, null, { timeout: 30_000 });

  const look = await page.evaluate(() => {
    const c = document.getElementById('view');
    const data = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    // The default scene's background is sRGB (24, 28, 38): count what differs from it.
    let object = 0;
    const colours = new Set();
    for (let i = 0; i < data.length; i += 4) {
      if (Math.abs(data[i] - 24) + Math.abs(data[i + 1] - 28) + Math.abs(data[i + 2] - 38) > 30) object += 1;
      colours.add((data[i] >> 3) << 10 | (data[i + 1] >> 3) << 5 | (data[i + 2] >> 3));
    }
    return { object: object / (data.length / 4), colours: colours.size };
  });
  assert.ok(look.object > 0.1, `the bunny covers part of the frame (share ${look.object})`);
  assert.ok(look.colours > 50, `the frame is shaded, not flat (${look.colours} colours)`);

  await gazeAt(page, 0.25, 0.3);
  const first = await markerCentroid(page);
  assert.ok(first, 'the marker is visible');
  assert.ok(Math.abs(first.x - 0.25 * first.w) < 3 && Math.abs(first.y - 0.3 * first.h) < 3,
    `marker at (${first.x.toFixed(1)}, ${first.y.toFixed(1)}) for gaze (0.25, 0.3) of ${first.w}x${first.h}`);

  await gazeAt(page, 0.75, 0.7);
  const second = await markerCentroid(page);
  assert.ok(Math.abs(second.x - 0.75 * second.w) < 3 && Math.abs(second.y - 0.7 * second.h) < 3,
    `marker at (${second.x.toFixed(1)}, ${second.y.toFixed(1)}) for gaze (0.75, 0.7)`);
  assert.ok(second.x - first.x > 0.4 * first.w, 'the marker moved with the mouse');

  // The overlay reports frame rate and a measured gaze-to-display latency.
  await page.waitForFunction(() => /gaze→display p50\s+\d/.test(document.getElementById('overlay').textContent),
    null, { timeout: 10_000 });
  const overlay = await page.locator('#overlay').textContent();
  assert.match(overlay, /fps\s+\d+/);

  mkdirSync(artifacts, { recursive: true });
  await page.screenshot({ path: join(artifacts, 'page.png') });
  assert.deepEqual(consoleErrors, [], 'no errors in the browser console');
  const errors = await page.evaluate(() => window.fovea.errors);
  assert.deepEqual(errors, [], 'the server reported no protocol errors to the page');
  await page.close();
});

test('auto gaze drives the frames with the synthetic eye', async () => {
  const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  await page.goto(`${baseUrl}/`);
  await page.waitForFunction(() => window.fovea && window.fovea.framesShown >= 1, null, { timeout: 30_000 });
  await page.check('#auto-gaze');
  // Without touching the mouse, frames keep arriving for gaze positions that change.
  const seen = await page.evaluate(async () => {
    const positions = new Set();
    const until = performance.now() + 8000;
    while (performance.now() < until && positions.size < 4) {
      const h = window.fovea.lastHeader;
      if (h && h.seq !== null) positions.add(`${h.gaze.x.toFixed(3)},${h.gaze.y.toFixed(3)}`);
      await new Promise((r) => setTimeout(r, 100));
    }
    return positions.size;
  });
  assert.ok(seen >= 4, `the synthetic eye moved the gaze (${seen} distinct positions)`);
  assert.deepEqual(consoleErrors, []);
  assert.deepEqual(await page.evaluate(() => window.fovea.errors), []);
  await page.close();
});

test('the cornell scene streams its radiosity preview and it converges', async () => {
  const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  await page.goto(`${baseUrl}/`);
  await page.waitForFunction(() => window.fovea && window.fovea.framesShown >= 1, null, { timeout: 30_000 });
  await page.selectOption('#scene', 'cornell');
  await page.check('#auto-gaze');
  // The solve starts when the scene loads; frames come at once, lit by the preview.
  const first = await page.waitForFunction(() => window.fovea.lastHeader?.radiosity, null, { timeout: 60_000 });
  const early = await first.jsonValue();
  const done = await page.waitForFunction(() => window.fovea.lastHeader?.radiosity?.converged && window.fovea.lastHeader.radiosity,
    null, { timeout: 180_000, polling: 250 });
  const late = await done.jsonValue();
  assert.ok(late.unshot < 0.001 && late.unshot < early.unshot, `unshot ${early.unshot} → ${late.unshot}`);
  await page.waitForFunction(() => /radiosity converged: \d+ shots/.test(document.getElementById('overlay').textContent),
    null, { timeout: 10_000 });
  mkdirSync(artifacts, { recursive: true });
  await page.screenshot({ path: join(artifacts, 'cornell.png') });
  assert.deepEqual(consoleErrors, []);
  assert.deepEqual(await page.evaluate(() => window.fovea.errors), []);
  await page.close();
});
