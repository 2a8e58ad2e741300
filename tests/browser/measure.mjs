// Measures `kardia explore` in chromium (a script, not a test): for each surface, the time
// from an input event (a drag step, handled at once by the page) to the first coarse frame
// drawn and to the full 800×600 frame at 1 sample, and frames drawn per second during a
// steady drag. Usage: node tests/browser/measure.mjs URL [RUNS] [SCREENSHOT_DIR]
import { chromium } from "playwright-core";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";

const [url, runsArg, shots] = process.argv.slice(2);
const runs = Number(runsArg || 5);
const profile = mkdtempSync(join(tmpdir(), "kardia-chromium-"));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  viewport: { width: 1200, height: 760 },
});
const page = context.pages()[0] || (await context.newPage());
const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];

for (const preset of ["heart", "barth_sextic"]) {
  await page.goto("about:blank");
  await page.goto(`${url}#mode=equation&preset=${preset}&size=800x600`);
  await page.waitForFunction(() => window.kardia.frames.some((f) => f.width === 800 && f.spp === 1), null, { timeout: 120000 });
  if (shots) {
    await page.waitForFunction(() => window.kardia.frames.at(-1).spp >= 8, null, { timeout: 120000 }).catch(() => {});
    await page.screenshot({ path: join(shots, `explorer_${preset}.png`) });
  }
  const box = await page.locator("#view").boundingBox();
  const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
  const coarse = [], full = [], passMs = [];
  for (let i = 0; i < runs; i++) {
    const seq = await page.evaluate(() => window.kardia.sent());
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    await page.mouse.move(cx + 12, cy + 2);
    await page.mouse.up();
    await page.waitForFunction((s) => window.kardia.frames.some((f) => f.seq > s && f.width === 800), seq, { timeout: 120000 });
    const frames = await page.evaluate((s) => window.kardia.frames.filter((f) => f.seq > s), seq);
    coarse.push(frames[0].sinceInput);
    const f = frames.find((f) => f.width === 800);
    full.push(f.sinceInput);
    passMs.push(f.ms);
  }
  // A steady drag: one move every 16 ms for 3 s.
  const seqBefore = await page.evaluate(() => window.kardia.sent());
  const start = Date.now();
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  let i = 0;
  while (Date.now() - start < 3000) {
    i += 1;
    await page.mouse.move(cx + 100 * Math.sin(i / 20), cy + 30 * Math.cos(i / 20));
    await page.waitForTimeout(16);
  }
  await page.mouse.up();
  const seconds = (Date.now() - start) / 1000;
  const drawn = await page.evaluate((s) => window.kardia.frames.filter((f) => f.seq > s).length, seqBefore);
  const sent = (await page.evaluate(() => window.kardia.sent())) - seqBefore;
  console.log(JSON.stringify({
    surface: preset,
    runs,
    first_coarse_ms_median: Math.round(median(coarse)),
    first_coarse_ms: coarse.map(Math.round),
    full_800x600_1spp_ms_median: Math.round(median(full)),
    full_ms: full.map(Math.round),
    full_pass_render_ms_median: Math.round(median(passMs)),
    drag_frames_per_second: +(drawn / seconds).toFixed(1),
    drag_views_sent_per_second: +(sent / seconds).toFixed(1),
  }));
}
await context.close();
rmSync(profile, { recursive: true, force: true });
