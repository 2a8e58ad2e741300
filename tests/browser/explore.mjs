// Browser tests of `kardia explore` in Debian's chromium, driven by playwright-core (which
// downloads no browser). Usage: node tests/browser/explore.mjs URL
// Run by tests/it/explore_browser.rs, which starts the server on 127.0.0.1:0.
import { chromium } from "playwright-core";
import { mkdtempSync, rmSync, writeFileSync, readFileSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { tmpdir } from "node:os";
import { join } from "node:path";
import assert from "node:assert/strict";
import pngjs from "pngjs";

const url = process.argv[2];
if (!url) throw new Error("usage: node tests/browser/explore.mjs URL");

const profile = mkdtempSync(join(tmpdir(), "kardia-chromium-"));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: [
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
  ],
  viewport: { width: 1000, height: 640 },
});
const page = context.pages()[0] || (await context.newPage());
const pageErrors = [];
page.on("pageerror", (e) => pageErrors.push(e.message));

let passed = 0, failed = 0;
async function check(name, body) {
  const start = Date.now();
  try {
    await body();
    passed += 1;
    console.log(`ok - ${name} (${Date.now() - start} ms)`);
  } catch (e) {
    failed += 1;
    console.log(`not ok - ${name}: ${e.stack || e}`);
    await page.screenshot({ path: join(tmpdir(), `kardia-failed-${passed + failed}.png`) }).catch(() => {});
  }
}

// The canvas's pixels summarised: mean colour, fraction of "red" pixels, and a sample grid.
const canvasStats = () => page.evaluate(() => {
  const c = document.getElementById("view");
  const data = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
  let r = 0, g = 0, b = 0, red = 0;
  const n = data.length / 4;
  for (let i = 0; i < data.length; i += 4) {
    r += data[i]; g += data[i + 1]; b += data[i + 2];
    if (data[i] > 120 && data[i] > 2 * data[i + 1] && data[i] > 2 * data[i + 2]) red += 1;
  }
  const grid = [];
  for (let y = 0; y < 16; y++) for (let x = 0; x < 16; x++) {
    const i = (Math.floor(((y + 0.5) * c.height) / 16) * c.width + Math.floor(((x + 0.5) * c.width) / 16)) * 4;
    grid.push(data[i], data[i + 1], data[i + 2]);
  }
  return { width: c.width, height: c.height, mean: [r / n, g / n, b / n], red: red / n, grid };
});
const difference = (a, b) => a.grid.reduce((s, v, i) => s + Math.abs(v - b.grid[i]), 0) / a.grid.length;

// Waits for a full-size frame of a request newer than `afterSeq`.
async function fullFrameAfter(afterSeq, timeout = 60000) {
  await page.waitForFunction((after) => window.kardia.frames.some(
    (f) => f.seq > after && f.width === f.view_width && f.height === f.view_height), afterSeq, { timeout });
  return page.evaluate(() => window.kardia.sent());
}
const sentSeq = () => page.evaluate(() => window.kardia.sent());

await check("the page loads and the heart appears", async () => {
  await page.goto(url);
  await fullFrameAfter(0);
  const stats = await canvasStats();
  assert.ok(stats.red > 0.08, `red fraction ${stats.red}`);
  const status = await page.textContent("#status");
  assert.match(status, /\d+×\d+ · \d+ spp · \d+ ms\/pass · [\d.]+ M rays\/s/);
});

await check("a drag changes the view", async () => {
  const before = await canvasStats();
  const seq = await sentSeq();
  const box = await page.locator("#view").boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) await page.mouse.move(box.x + box.width / 2 + 15 * i, box.y + box.height / 2 + 3 * i);
  await page.mouse.up();
  await fullFrameAfter(seq);
  const last = await sentSeq();
  await fullFrameAfter(last - 1);
  const after = await canvasStats();
  assert.ok(difference(before, after) > 8, `mean difference ${difference(before, after)}`);
  const text = await page.inputValue("#scene-text");
  assert.doesNotMatch(text.split("\n").find((l) => /^CAMERA/i.test(l)), /\(6, 1\.2, 0\.9\)/, "the CAMERA line follows the view");
});

await check("a bad equation shows its error and position, a good one recovers", async () => {
  await page.click("#mode-equation");
  await page.click('#gallery button[data-preset="sphere16"]');
  await fullFrameAfter((await sentSeq()) - 1);
  const good = await canvasStats();
  await page.fill("#equation", "x^2 + y^2 + * z^2 - 1");
  await page.waitForSelector("#problem:not([hidden])");
  const problem = await page.evaluate(() => window.kardia.lastProblem);
  assert.match(problem.message, /^explore\.scene:8:\d+: invalid equation: expected a number, x, y, z or '\(' here, not '\*'/);
  assert.equal(await page.textContent("#equation-marked mark"), "*");
  assert.ok((await page.textContent("#problem")).includes("╰── here"));
  const kept = await canvasStats();
  assert.ok(difference(good, kept) < 1, "the last good image stays");
  const seq = await sentSeq();
  await page.fill("#equation", "x^2 + y^2 + z^2 - 1");
  await fullFrameAfter(seq - 1);
  assert.ok(await page.isHidden("#problem"));
  assert.ok(await page.isHidden("#equation-marked"));
});

await check("a preset slider changes the image", async () => {
  await page.click('#gallery button[data-preset="torus"]');
  await fullFrameAfter((await sentSeq()) - 1);
  await page.waitForFunction(() => document.getElementById("equation").value.includes("4*1^2"));
  const before = await canvasStats();
  await page.evaluate(() => {
    const r = document.getElementById("param-1");
    r.value = "0.8";
    r.dispatchEvent(new Event("input", { bubbles: true }));
  });
  const seq = await sentSeq();
  await fullFrameAfter(seq - 1);
  const after = await canvasStats();
  assert.ok(difference(before, after) > 8, `mean difference ${difference(before, after)}`);
  await page.waitForFunction(() => document.getElementById("equation").value.includes("0.8^2"));
});

await check("a study view differs from the shaded view", async () => {
  const shaded = await canvasStats();
  const seq = await sentSeq();
  await page.selectOption("#study", "normals");
  await fullFrameAfter(seq);
  const normals = await canvasStats();
  assert.ok(difference(shaded, normals) > 20, `mean difference ${difference(shaded, normals)}`);
  await page.selectOption("#study", "shaded");
  await fullFrameAfter(seq + 1);
});

await check("a root-finder study view shows its legend, whose colours are the image's", async () => {
  assert.ok(await page.isHidden("#legend"), "no legend for the shaded view");
  const seq = await sentSeq();
  await page.selectOption("#study", "path");
  await fullFrameAfter(seq);
  await page.waitForSelector("#legend:not([hidden]) .swatch");
  const swatches = await page.$$eval("#legend .swatch", (s) => s.map((e) => e.dataset.colour));
  assert.ok(swatches.includes("#4c9be8") && swatches.length >= 5, swatches.join(" "));
  // The heart's middle (the default heart fills the centre): all of a pixel's samples are
  // settled the same way there, so the pixel is exactly a legend colour.
  const centre = await page.evaluate(() => {
    const c = document.getElementById("view");
    const d = c.getContext("2d").getImageData(c.width >> 1, c.height >> 1, 1, 1).data;
    return "#" + [d[0], d[1], d[2]].map((v) => v.toString(16).padStart(2, "0")).join("");
  });
  assert.ok(swatches.includes(centre), `centre ${centre} not in ${swatches.join(" ")}`);
  await page.selectOption("#study", "shaded");
  await fullFrameAfter(seq + 1);
  assert.ok(await page.isHidden("#legend"));
});

await check("Save PNG equals `kardia render` of Copy scene", async () => {
  const kardia = process.env.KARDIA_BIN;
  assert.ok(kardia, "KARDIA_BIN names the kardia binary");
  await page.fill("#save-width", "160");
  await page.fill("#save-height", "120");
  await page.fill("#save-spp", "2");
  await page.evaluate(() => { window.kardia.lastPng = null; });
  await page.click("#save");
  await page.waitForFunction(() => window.kardia.lastPng, null, { timeout: 60000 });
  await page.click("#copy-scene");
  const scene = await page.evaluate(() => window.kardia.clipboard);
  const dir = mkdtempSync(join(tmpdir(), "kardia-save-"));
  writeFileSync(join(dir, "copied.scene"), scene);
  execFileSync(kardia, ["render", join(dir, "copied.scene"), "-o", join(dir, "cli.png"),
    "--width", "160", "--height", "120", "--spp", "2", "--quiet"]);
  const cli = readFileSync(join(dir, "cli.png")).toString("base64");
  rmSync(dir, { recursive: true, force: true });
  const same = await page.evaluate(async (cliBase64) => {
    const pixels = async (blob) => {
      const bitmap = await createImageBitmap(blob, { colorSpaceConversion: "none", premultiplyAlpha: "none" });
      const c = new OffscreenCanvas(bitmap.width, bitmap.height);
      const g = c.getContext("2d");
      g.drawImage(bitmap, 0, 0);
      return { w: bitmap.width, h: bitmap.height, data: g.getImageData(0, 0, bitmap.width, bitmap.height).data };
    };
    const bytes = Uint8Array.from(atob(cliBase64), (ch) => ch.charCodeAt(0));
    const a = await pixels(window.kardia.lastPng);
    const b = await pixels(new Blob([bytes], { type: "image/png" }));
    let differing = 0;
    for (let i = 0; i < a.data.length; i++) if (a.data[i] !== b.data[i]) differing++;
    return { size: [a.w, a.h, b.w, b.h], differing };
  }, cli);
  assert.deepEqual(same.size, [160, 120, 160, 120]);
  assert.equal(same.differing, 0, "every pixel equal");
});

await check("a transparent Save PNG equals `kardia render --alpha` of Copy scene", async () => {
  const kardia = process.env.KARDIA_BIN;
  assert.ok(kardia, "KARDIA_BIN names the kardia binary");
  await page.click('#gallery button[data-preset="heart"]');
  await fullFrameAfter((await sentSeq()) - 1);
  const [w, h, spp] = ["160", "120", "2"];
  await page.fill("#save-width", w);
  await page.fill("#save-height", h);
  await page.fill("#save-spp", spp);
  await page.check("#save-alpha");
  assert.match(page.url(), /[#&]alpha=1(&|$)/, "the option is in the URL");
  await page.evaluate(() => { window.kardia.lastPng = null; });
  await page.click("#save");
  await page.waitForFunction(() => window.kardia.lastPng, null, { timeout: 60000 });
  const saved = Buffer.from(await page.evaluate(async () => {
    const bytes = new Uint8Array(await window.kardia.lastPng.arrayBuffer());
    let s = "";
    for (const b of bytes) s += String.fromCharCode(b);
    return btoa(s);
  }), "base64");
  await page.click("#copy-scene");
  const scene = await page.evaluate(() => window.kardia.clipboard);
  const dir = mkdtempSync(join(tmpdir(), "kardia-save-"));
  writeFileSync(join(dir, "copied.scene"), scene);
  execFileSync(kardia, ["render", join(dir, "copied.scene"), "-o", join(dir, "cli.png"),
    "--width", w, "--height", h, "--spp", spp, "--alpha", "--quiet"]);
  const cli = readFileSync(join(dir, "cli.png"));
  rmSync(dir, { recursive: true, force: true });
  // Decoded exactly (a canvas would premultiply), straight RGBA as the files hold it.
  const a = pngjs.PNG.sync.read(saved), b = pngjs.PNG.sync.read(cli);
  assert.deepEqual([a.width, a.height, a.colorType, a.depth], [160, 120, 6, 8], "the saved PNG is 8-bit RGBA");
  assert.deepEqual([b.width, b.height, b.colorType, b.depth], [160, 120, 6, 8]);
  const alphaAt = (png, x, y) => png.data[(y * png.width + x) * 4 + 3];
  assert.equal(alphaAt(a, 0, 0), 0, "a corner is transparent");
  assert.equal(alphaAt(a, 80, 60), 255, "the heart's centre is opaque");
  const partial = a.data.filter((v, i) => i % 4 === 3 && v > 0 && v < 255).length;
  assert.ok(partial > 0, "the silhouette is partly transparent");
  let differing = 0;
  for (let i = 0; i < a.width * a.height; i++) {
    if (a.data.readUInt32BE(4 * i) !== b.data.readUInt32BE(4 * i)) differing++;
  }
  assert.equal(differing, 0, "every RGBA pixel equal");
});

await check("a copied link restores the view", async () => {
  const box = await page.locator("#view").boundingBox();
  await page.mouse.move(box.x + 100, box.y + 100);
  await page.mouse.down();
  await page.mouse.move(box.x + 160, box.y + 70, { steps: 5 });
  await page.mouse.up();
  await page.click("#copy-link");
  const link = await page.evaluate(() => window.kardia.clipboard);
  const scene = await page.evaluate(() => window.kardia.state && document.getElementById("equation").value);
  const text = await page.evaluate(() => window.kardia.currentScene());
  const second = await context.newPage();
  second.on("pageerror", (e) => pageErrors.push("second page: " + e.message));
  await second.goto(link);
  await second.waitForFunction(() => window.kardia.frames.some((f) => f.width === f.view_width), null, { timeout: 60000 });
  assert.equal(await second.evaluate(() => window.kardia.currentScene()), text);
  assert.equal(await second.inputValue("#equation"), scene);
  assert.equal(await second.evaluate(() => window.kardia.state.mode), "equation");
  assert.ok(await second.isChecked("#save-alpha"), "the transparent background comes back");
  await second.close();
});

assert.deepEqual(pageErrors, [], "no script errors on the page");
await context.close();
rmSync(profile, { recursive: true, force: true });
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 && pageErrors.length === 0 ? 0 : 1);
