// Measures `kardia explore` in chromium (a script, not a test): for the heart and Barth's
// sextic in equation mode at a fixed 800×600 view, the time from an input event (a drag step;
// the page sends the view from its event handler) to the first coarse frame drawn and to the
// full 800×600 frame at 1 sample, over RUNS drag steps, and the frames drawn per second during
// RUNS steady drags of 3 s, alone and while a second page (in a browser of its own) saves 1600×1200 images at 16 spp
// one after the other (with, for those, the time from releasing the mouse to the full frame);
// prints one JSON line per surface with the medians (and every run).
//
// Usage:
//   node tests/browser/measure.mjs --kardia target/release/kardia [RUNS] [SCREENSHOT_DIR]
//     starts `kardia explore --port 0` itself (stopped at the end), or
//   node tests/browser/measure.mjs URL [RUNS] [SCREENSHOT_DIR]
//     measures a server already running at URL.
// RUNS defaults to 5; with SCREENSHOT_DIR, a screenshot of each surface at ≥ 8 spp is saved
// there as explorer_PRESET.png.
import { chromium } from "playwright-core";
import { spawn } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import { loadavg, tmpdir } from "node:os";
import { join } from "node:path";

const args = process.argv.slice(2);
let server = null;
let url;
if (args[0] === "--kardia") {
  if (!args[1]) throw new Error("usage: measure.mjs --kardia BINARY [RUNS] [SCREENSHOT_DIR]");
  server = spawn(args[1], ["explore", "--port", "0"], { stdio: ["ignore", "pipe", "inherit"] });
  url = await new Promise((resolve, reject) => {
    let out = "";
    server.stdout.on("data", (chunk) => {
      out += chunk;
      const m = out.match(/kardia explore: (http:\/\/\S+)/);
      if (m) resolve(m[1]);
    });
    server.on("exit", (code) => reject(new Error(`kardia explore exited (${code}) before printing its URL`)));
    setTimeout(() => reject(new Error("kardia explore printed no URL within 30 s")), 30000);
  });
  args.splice(0, 2);
} else {
  url = args.shift();
  if (!url || !/^http:\/\//.test(url)) {
    throw new Error("usage: measure.mjs (--kardia BINARY | URL) [RUNS] [SCREENSHOT_DIR]");
  }
}
const runs = Number(args[0] || 5);
if (!Number.isInteger(runs) || runs < 1) throw new Error(`RUNS must be a whole number ≥ 1, not ${args[0]}`);
const shots = args[1];
const [W, H] = [800, 600];

// Each browser gets a fresh profile, removed at the end.
const profiles = [];
const launch = () => {
  const profile = mkdtempSync(join(tmpdir(), "kardia-chromium-"));
  profiles.push(profile);
  return chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync"],
    viewport: { width: 1200, height: 760 },
  });
};
const context = await launch();
// The saving page is another person's: a browser of its own. (A second page in the same
// headless chromium slows the first one's input events to a few a second, whatever the
// server does: 7 mouse moves in 3 s instead of 28, measured with an idle second page.)
const otherBrowser = await launch();
const loadAverage = () => Math.round(loadavg()[0] * 10) / 10;
const page = context.pages()[0] || (await context.newPage());
const pageErrors = [];
page.on("pageerror", (e) => pageErrors.push(e.message));
const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};
const isFull = (f) => f.width === W && f.height === H;
const sent = () => page.evaluate(() => window.kardia.sent());
// Frames of requests after `seq` received so far (the page keeps the last 200).
const framesAfter = (seq) => page.evaluate((s) => window.kardia.frames.filter((f) => f.seq > s), seq);

try {
  for (const preset of ["heart", "barth_sextic"]) {
    const loadBefore = loadAverage();
    await page.goto("about:blank");
    await page.goto(`${url}#mode=equation&preset=${preset}&size=${W}x${H}`);
    await page.waitForFunction(([w, h]) => window.kardia.frames.some((f) => f.width === w && f.height === h),
      [W, H], { timeout: 120000 });
    if (shots) {
      await page.waitForFunction(() => window.kardia.frames.at(-1).spp >= 8, null, { timeout: 120000 }).catch(() => {});
      await page.screenshot({ path: join(shots, `explorer_${preset}.png`) });
    }
    const box = await page.locator("#view").boundingBox();
    const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
    const coarse = [], full = [], fullPassMs = [], coarsePassMs = [];
    for (let i = 0; i < runs; i++) {
      // Each step starts while the previous view is refining, as when a user drags again.
      await page.waitForTimeout(300);
      const seq = await sent();
      await page.mouse.move(cx, cy);
      await page.mouse.down();
      await page.mouse.move(cx + 12, cy + 2);
      await page.mouse.up();
      if ((await sent()) !== seq + 1) throw new Error(`a drag step sent ${(await sent()) - seq} views, not 1`);
      await page.waitForFunction(([s, w, h]) => window.kardia.frames.some((f) => f.seq > s && f.width === w && f.height === h),
        [seq, W, H], { timeout: 120000 });
      const frames = await framesAfter(seq);
      const first = frames[0];
      if (isFull(first) || first.pass !== 0) throw new Error(`the first frame was not a coarse one: ${JSON.stringify(first)}`);
      const f = frames.find(isFull);
      if (f.spp !== 1) throw new Error(`the first full-size frame has ${f.spp} spp`);
      coarse.push(first.sinceInput);
      coarsePassMs.push(first.ms);
      full.push(f.sinceInput);
      fullPassMs.push(f.ms);
    }
    // Steady drags: one move every 16 ms for 3 s each; the result's frame rates, and the time
    // from the release to the full frame of the last view.
    const steadyDrag = async () => {
      await page.waitForTimeout(300);
      const seqBefore = await sent();
      await page.mouse.move(cx, cy);
      await page.mouse.down();
      const start = Date.now();
      let step = 0;
      while (Date.now() - start < 3000) {
        step += 1;
        await page.mouse.move(cx + 100 * Math.sin(step / 20), cy + 30 * Math.cos(step / 20));
        await page.waitForTimeout(16);
      }
      const seconds = (Date.now() - start) / 1000;
      const drawn = await framesAfter(seqBefore);
      const released = await page.evaluate(() => performance.now());
      await page.mouse.up();
      const last = await sent();
      await page.waitForFunction(([s, w, h]) => window.kardia.frames.some((f) => f.seq >= s && f.width === w && f.height === h),
        [last, W, H], { timeout: 120000 });
      const fullAt = await page.evaluate(([s, w, h]) => {
        const f = window.kardia.frames.find((f) => f.seq >= s && f.width === w && f.height === h);
        return f.receivedAt;
      }, [last, W, H]);
      return {
        fps: drawn.length / seconds,
        fullFps: drawn.filter(isFull).length / seconds,
        sentPerSecond: ((await sent()) - seqBefore) / seconds,
        releaseToFull: fullAt - released,
      };
    };
    const alone = [];
    for (let i = 0; i < runs; i++) alone.push(await steadyDrag());
    // The same beside a second page that saves 1600×1200 images at 16 spp, one after another.
    const saver = otherBrowser.pages()[0] || (await otherBrowser.newPage());
    saver.on("pageerror", (e) => pageErrors.push("saving page: " + e.message));
    await saver.goto(`${url}#mode=equation&preset=${preset}&size=400x300&save=1600x1200x16`);
    await saver.waitForFunction(() => window.kardia.frames.length > 0, null, { timeout: 120000 });
    await saver.evaluate(() => {
      window.keepSaving = true;
      const again = () => {
        if (!window.keepSaving) return;
        window.kardia.lastPng = null;
        document.getElementById("save").click();
        const wait = () => (window.kardia.lastPng ? again() : setTimeout(wait, 20));
        wait();
      };
      again();
    });
    await saver.waitForTimeout(500);
    const beside = [];
    for (let i = 0; i < runs; i++) beside.push(await steadyDrag());
    const saves = await saver.evaluate(() => { window.keepSaving = false; return window.kardia.messages.filter((m) => /^saved /.test(m)).length; });
    await saver.evaluate(() => document.getElementById("save-cancel").click());
    await saver.goto("about:blank");
    const fps = alone.map((r) => r.fps), fullFps = alone.map((r) => r.fullFps);
    const sentPerSecond = alone.map((r) => r.sentPerSecond);
    const round = (xs) => xs.map((x) => Math.round(x));
    const tenth = (x) => Math.round(x * 10) / 10;
    console.log(JSON.stringify({
      surface: preset,
      runs,
      first_coarse_ms_median: Math.round(median(coarse)),
      first_coarse_ms: round(coarse),
      coarse_pass_render_ms_median: tenth(median(coarsePassMs)),
      full_800x600_1spp_ms_median: Math.round(median(full)),
      full_ms: round(full),
      full_pass_render_ms_median: Math.round(median(fullPassMs)),
      drag_frames_per_second_median: tenth(median(fps)),
      drag_full_size_frames_per_second_median: tenth(median(fullFps)),
      drag_views_sent_per_second_median: tenth(median(sentPerSecond)),
      release_to_full_ms_median: Math.round(median(alone.map((r) => r.releaseToFull))),
      beside_saving_drag_frames_per_second_median: tenth(median(beside.map((r) => r.fps))),
      beside_saving_drag_frames_per_second: beside.map((r) => tenth(r.fps)),
      beside_saving_drag_views_sent_per_second_median: tenth(median(beside.map((r) => r.sentPerSecond))),
      beside_saving_release_to_full_ms_median: Math.round(median(beside.map((r) => r.releaseToFull))),
      beside_saving_release_to_full_ms: round(beside.map((r) => r.releaseToFull)),
      saves_finished_meanwhile: saves,
      load_average_before: loadBefore,
      load_average_after: loadAverage(),
    }));
  }
  if (pageErrors.length) throw new Error(`script errors on the page: ${pageErrors.join("; ")}`);
} finally {
  await context.close();
  await otherBrowser.close();
  for (const profile of profiles) rmSync(profile, { recursive: true, force: true });
  if (server) server.kill("SIGINT");
}
