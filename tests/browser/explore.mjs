// Browser tests of `kardia explore` in Debian's chromium, driven by playwright-core (which
// downloads no browser). Usage: node tests/browser/explore.mjs URL
// Run by tests/it/explore_browser.rs, which starts the server on 127.0.0.1:0.
import { chromium } from "playwright-core";
import { mkdtempSync, rmSync, writeFileSync, readFileSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { cpus, loadavg, tmpdir } from "node:os";
import { join } from "node:path";
import assert from "node:assert/strict";
import pngjs from "pngjs";

const url = process.argv[2];
if (!url) throw new Error("usage: node tests/browser/explore.mjs URL");

const profile = mkdtempSync(join(tmpdir(), "kardia-chromium-"));
const browserOptions = {
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: [
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
  ],
  viewport: { width: 1000, height: 640 },
};
const context = await chromium.launchPersistentContext(profile, browserOptions);
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

// Records, from now on, whether an element ever got a class (a MutationObserver in the page).
const watchClass = (selector, cls, key) => page.evaluate(([selector, cls, key]) => {
  window[key] = false;
  const el = document.querySelector(selector);
  if (el.classList.contains(cls)) window[key] = true;
  new MutationObserver(() => { if (el.classList.contains(cls)) window[key] = true; })
    .observe(el, { attributes: true, attributeFilter: ["class"] });
}, [selector, cls, key]);
const boxes = (selectors) => page.evaluate((selectors) => selectors.map((s) => {
  const r = document.querySelector(s).getBoundingClientRect();
  return [s, Math.round(r.x), Math.round(r.y), Math.round(r.width), Math.round(r.height)].join(" ");
}), selectors);

await check("first contact: equation mode on the heart, a gallery of kardia's thumbnails, a plain status", async () => {
  await page.goto(url);
  await fullFrameAfter(0);
  const stats = await canvasStats();
  assert.ok(stats.red > 0.08, `red fraction ${stats.red}`);
  assert.equal(await page.evaluate(() => window.kardia.state.mode), "equation");
  assert.ok(await page.isVisible("#equation"), "the equation box is on screen");
  assert.equal(await page.getAttribute('#gallery button[data-preset="heart"]', "aria-pressed"), "true");
  const ids = await page.$$eval("#gallery button", (b) => b.map((e) => e.dataset.preset));
  for (const id of ["heart", "torus", "cayley", "clebsch", "kummer", "roman", "togliatti", "barth_sextic",
    "labs", "endrass", "barth_decic", "chmutov", "sarti"]) assert.ok(ids.includes(id), `${id} in the gallery`);
  // Every thumbnail is a 160×120 image the server rendered.
  await page.waitForFunction(() => [...document.querySelectorAll("#gallery img")]
    .every((i) => i.complete && i.naturalWidth > 0), null, { timeout: 120000 });
  const sizes = await page.$$eval("#gallery img", (i) => i.map((e) => `${e.naturalWidth}x${e.naturalHeight}`));
  assert.ok(sizes.every((s) => s === "160x120"), sizes.join(" "));
  assert.ok((await page.textContent("#about")).length > 40, "the heart's text is shown");
  await page.waitForFunction(() => /^(refining: \d+ \/ 64 samples|done: 64 samples a pixel)$/
    .test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  assert.doesNotMatch(await page.textContent("#status-text"), /ms|rays/);
  assert.match(await page.textContent("#status-details"), /\d+×\d+ · \d+ spp · \d+ ms\/pass · [\d.]+ M rays\/s/);
  assert.ok(await page.isHidden("#status-details"), "the figures are behind the details toggle");
  assert.ok(Number(await page.getAttribute("#progress", "value")) >= 1);
});

await check("typing a torus one character at a time: no error, no half-typed canvas", async () => {
  await page.click('#gallery button[data-preset="sphere16"]');
  await fullFrameAfter((await sentSeq()) - 1);
  await watchClass("#equation-problem", "shown", "problemShown");
  await page.evaluate(() => {
    window.inputTimes = [];
    document.getElementById("equation").addEventListener("input", () => window.inputTimes.push(performance.now()));
  });
  const before = await sentSeq();
  const torus = "(x^2+y^2+z^2+0.91)^2 - 4*(x^2+y^2)";
  await page.fill("#equation", "");
  await page.type("#equation", torus, { delay: 20 });
  await page.waitForTimeout(400);
  const last = await sentSeq();
  await fullFrameAfter(last - 1);
  const { views, inputs } = await page.evaluate((b) => ({
    views: window.kardia.views.filter((v) => v.seq > b), inputs: window.inputTimes,
  }), before);
  // A view goes out only after the text has been still for about 150 ms: typing faster than
  // that sends the whole equation alone. (A browser stalled by a loaded machine leaves gaps
  // in the typing; a view may go out in such a gap, and only there.)
  const gaps = inputs.slice(1).map((t, i) => t - inputs[i]).filter((g) => g >= 140).length;
  for (const v of views) {
    const lastInput = Math.max(...inputs.filter((t) => t <= v.at));
    assert.ok(v.at - lastInput >= 140, `a view went out ${v.at - lastInput} ms after a keystroke`);
  }
  const typed = views.filter((v) => v.scene.includes(`"${torus}"`));
  assert.ok(typed.length >= 1, "the whole equation was sent");
  assert.ok(views.length - typed.length <= gaps, `${views.length - typed.length} half-typed views, ${gaps} pauses`);
  if (gaps === 0) assert.equal(await page.evaluate(() => window.problemShown), false, "the error box never showed");
  else console.log(`# typing stalled ${gaps} times (a loaded machine): the error box is not checked`);
  assert.ok((await canvasStats()).red > 0.04, "the torus is drawn");
  // A slower typist (5 characters a second): the pause adapts to their pace (twice it), so
  // the half-typed equations between keystrokes are not sent either.
  await page.fill("#equation", "");
  await page.waitForTimeout(1200);
  const slowBefore = await sentSeq();
  await page.evaluate(() => { window.inputTimes = []; });
  await page.type("#equation", torus, { delay: 200 });
  await page.waitForTimeout(800);
  await fullFrameAfter((await sentSeq()) - 1);
  const slow = await page.evaluate((b) => ({
    views: window.kardia.views.filter((v) => v.seq > b), inputs: window.inputTimes,
  }), slowBefore);
  const slowGaps = slow.inputs.slice(1).map((t, i) => t - slow.inputs[i]);
  const pace = [...slowGaps].sort((a, b) => a - b)[slowGaps.length >> 1];
  const stalls = slowGaps.filter((g) => g >= 1.8 * pace).length;
  // The first character comes before any pace is known: it may go out after 150 ms.
  const halfTyped = slow.views.map((v) => v.scene.match(/IMPLICIT "([^"]*)"/)?.[1])
    .filter((typed) => typed !== torus && typed !== torus[0]);
  assert.ok(slow.views.some((v) => v.scene.includes(`"${torus}"`)), "the whole equation was sent");
  assert.ok(halfTyped.length <= stalls, `typing at ${Math.round(pace)} ms a character sent ${halfTyped.length} ` +
    `half-typed views (${stalls} pauses of twice that): ${JSON.stringify(halfTyped)}`);
});

await check("an invalid equation: one plain sentence, the part marked, the last image dimmed, nothing moves", async () => {
  const good = await canvasStats();
  const layout = ["#sliders", "#bound", "#gallery", "#view", "#status", "#view-controls"];
  const before = await boxes(layout);
  const seq = await sentSeq();
  await page.fill("#equation", "x^2 + y^2 + * z^2 - 1");
  await page.press("#equation", "Enter");
  await page.waitForSelector("#equation-problem.shown");
  assert.equal(await sentSeq(), seq + 1, "Enter sent the view at once, once");
  const sentence = await page.textContent("#equation-sentence");
  assert.equal(sentence, "Expected a number, x, y, z or '(' here, not '*'.");
  const shown = await page.textContent("#equation-problem");
  assert.doesNotMatch(shown, /LIGHT|usage|IMPLICIT|explore\.scene|:\d+:\d+/);
  assert.equal(await page.textContent("#equation-marked mark"), "*");
  assert.ok(await page.evaluate(() => document.getElementById("view").classList.contains("stale")), "dimmed");
  assert.ok(difference(good, await canvasStats()) < 1, "the last good image stays");
  assert.deepEqual(await boxes(layout), before, "nothing moved when the error came");
  assert.equal(await page.getAttribute("#equation-problem", "role"), "alert");
  await page.fill("#equation", "x^2 + y^2 + z^2 - 1");
  await fullFrameAfter(seq + 1);
  assert.ok(!(await page.evaluate(() => document.getElementById("equation-problem").classList.contains("shown"))));
  assert.deepEqual(await boxes(layout), before, "nothing moved when the error went");
});

await check("an equation with no real points says there is nothing to draw, and the sentence goes with it", async () => {
  const layout = ["#sliders", "#bound", "#gallery", "#view", "#status", "#view-controls"];
  const before = await boxes(layout);
  const seq = await sentSeq();
  await page.fill("#equation", "x^2 + y^2 + z^2 + 1");
  await page.press("#equation", "Enter");
  await fullFrameAfter(seq);
  await page.waitForSelector("#equation-problem.shown.notice", { timeout: 10000 });
  assert.match(await page.textContent("#equation-sentence"), /^Nothing to draw: this surface has no real points inside the clip radius \d/);
  assert.ok(!(await page.evaluate(() => document.getElementById("equation").classList.contains("bad"))), "not an error");
  assert.deepEqual(await boxes(layout), before, "nothing moved when the sentence came");
  // A camera change keeps it (the surface is the same); a surface with points clears it.
  await page.focus("#view");
  await page.keyboard.press("ArrowLeft");
  await fullFrameAfter((await sentSeq()) - 1);
  assert.match(await page.textContent("#equation-sentence"), /^Nothing to draw/, "kept while the surface is the same");
  const again = await sentSeq();
  await page.fill("#equation", "x^2 + y^2 + z^2 - 1");
  await page.press("#equation", "Enter");
  await fullFrameAfter(again);
  assert.ok(!(await page.evaluate(() => document.getElementById("equation-problem").classList.contains("shown"))),
    "the sentence goes with a surface that has points");
  assert.deepEqual(await boxes(layout), before, "nothing moved when it went");
});

await check("a free letter gets a slider with editable bounds, kept in the URL", async () => {
  await page.fill("#equation", "x^2 + y^2 + z^2 - a");
  await page.press("#equation", "Enter");
  await page.waitForSelector("#letter-a");
  await fullFrameAfter((await sentSeq()) - 1);
  assert.match(page.url(), /letters=a%3A1%3A-2%3A2/);
  const big = await canvasStats();
  await page.fill("#letter-a-min", "0");
  await page.dispatchEvent("#letter-a-min", "change");
  await page.evaluate(() => {
    const r = document.getElementById("letter-a");
    r.value = "0.2";
    r.dispatchEvent(new Event("input", { bubbles: true }));
  });
  await fullFrameAfter((await sentSeq()) - 1);
  assert.match(page.url(), /letters=a%3A0.2%3A0%3A2/);
  assert.ok((await canvasStats()).red < big.red * 0.6, "a smaller sphere");
  assert.equal(await page.getAttribute("#letter-a", "aria-label"), "a");
});

await check("a new equation is framed, and Fit frames the surface from its extent", async () => {
  await page.fill("#equation", "x^2 + y^2 + z^2 - 0.04");
  await page.press("#equation", "Enter");
  await page.waitForFunction(() => window.kardia.extent && window.kardia.extent.max[0] < 0.5);
  await page.waitForFunction(() => Math.hypot(...window.kardia.state.camera.eye) < 3);
  await fullFrameAfter((await sentSeq()) - 1);
  const framed = (await canvasStats()).red;
  await page.click("#reset");
  await fullFrameAfter((await sentSeq()) - 1);
  const unframed = (await canvasStats()).red;
  assert.ok(framed > 5 * unframed && framed > 0.05, `framed ${framed}, from the default view ${unframed}`);
  await page.click("#fit");
  await fullFrameAfter((await sentSeq()) - 1);
  const fitted = (await canvasStats()).red;
  assert.ok(fitted > 5 * unframed && fitted > 0.05, `Fit: ${fitted}`);
});

await check("a drag changes the view and the scene's CAMERA line", async () => {
  await page.click("#mode-scene");
  await fullFrameAfter((await sentSeq()) - 1);
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

await check("a scene without CAMERA: an error on its line 10 is reported on line 10", async () => {
  const lines = [
    "# a scene of my own", "SIZE 320 240", "BACKGROUND (0.1, 0.1, 0.1)", "AMBIENT (0.1, 0.1, 0.1)",
    "", "LIGHT (5, 5, 5) (1, 1, 1)", "", "SPHERE (0, 0, 0) 1 (0.8, 0.2, 0.2)", "",
    "SPHERE (0, 0, 2) -1 (0.2, 0.8, 0.2)", "",
  ];
  await page.fill("#scene-text", lines.join("\n"));
  await page.waitForFunction(() => window.kardia.lastProblem, null, { timeout: 20000 });
  const problem = await page.evaluate(() => window.kardia.lastProblem);
  assert.equal(problem.line, 10, problem.message);
  assert.equal(await page.textContent("#scene-lines .bad"), "10\n");
  assert.match(await page.textContent("#status-text"), /line 10/);
  // The faulty part is marked in the text itself, at its line and column: the radius "-1".
  const mark = await page.evaluate(() => {
    const m = document.querySelector("#scene-marks mark");
    if (!m) return null;
    const area = document.getElementById("scene-text").getBoundingClientRect();
    const box = m.getBoundingClientRect();
    const before = document.getElementById("scene-marks").textContent.split("\n");
    return { text: m.textContent, line: Number(m.dataset.line), column: Number(m.dataset.column),
      top: box.top - area.top, left: box.left - area.left, width: box.width, before: before[9].slice(0, 17) };
  });
  assert.ok(mark, "a mark in the scene text");
  assert.deepEqual([mark.text, mark.line, mark.column, mark.before], ["-1", 10, 18, "SPHERE (0, 0, 2) "]);
  // 4 px of padding, 9 lines of 12 px × 1.35 above it, 17 characters of a monospace font
  // (about 0.6 em each) before it.
  assert.ok(Math.abs(mark.top - (4 + 9 * 16.2)) < 3, `the mark is on line 10: ${mark.top} px from the top`);
  const charWidth = mark.width / 2;
  assert.ok(Math.abs(mark.left - (4 + 17 * charWidth)) < 3, `the mark is at column 18: ${mark.left} px`);
  await page.selectOption("#scene-file", "heart.scene");
  await fullFrameAfter((await sentSeq()) - 1);
  await page.click("#mode-equation");
  await fullFrameAfter((await sentSeq()) - 1);
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

await check("links: any subset of keys opens a sensible view; bad values get a message and a fallback", async () => {
  const base = url.replace(/\/$/, "");
  const second = await context.newPage();
  second.on("pageerror", (e) => pageErrors.push("links page: " + e.message));
  const fullFrame = () => second.waitForFunction(() => window.kardia.frames.some((f) => f.width === f.view_width),
    null, { timeout: 60000 });
  await second.goto(`${base}/#preset=torus`);
  await fullFrame();
  assert.equal(await second.evaluate(() => window.kardia.state.presetId), "torus");
  await second.waitForFunction(() => document.getElementById("equation").value.includes("4*1^2"));
  await second.goto("about:blank");
  await second.goto(`${base}/#mode=equation&preset=nonsense&params=1,2,3`);
  await fullFrame();
  assert.equal(await second.evaluate(() => window.kardia.state.presetId), "heart");
  assert.match(await second.textContent("#message"), /Unknown surface 'nonsense': the heart is shown instead/);
  await second.goto("about:blank");
  await second.goto(`${base}/#mode=equation&preset=torus&size=10000x10000&bound=-5&camera=1,2`);
  const widths = await second.evaluate(() => new Promise((resolve) => {
    const seen = [];
    const c = document.getElementById("view");
    const poll = () => { seen.push(c.width); if (window.kardia.frames.length) resolve(seen); else setTimeout(poll, 5); };
    poll();
  }));
  assert.ok(widths.every((w) => w <= 4096), `canvas widths ${[...new Set(widths)].join(" ")}`);
  const messages = await second.textContent("#message");
  assert.match(messages, /size 10000×10000 is over the limits/);
  assert.match(messages, /camera is not 10 numbers/);
  await fullFrame();
  await second.close();
});

await check("Back and Forward step through the settled views", async () => {
  await page.click('#gallery button[data-preset="torus"]');
  await fullFrameAfter((await sentSeq()) - 1);
  await page.waitForTimeout(1200);
  await page.click('#gallery button[data-preset="cayley"]');
  await fullFrameAfter((await sentSeq()) - 1);
  await page.waitForTimeout(1200);
  await page.goBack();
  await page.waitForFunction(() => window.kardia.state.presetId === "torus");
  await fullFrameAfter((await sentSeq()) - 1);
  await page.goForward();
  await page.waitForFunction(() => window.kardia.state.presetId === "cayley");
  await fullFrameAfter((await sentSeq()) - 1);
});

await check("the torus's R slider carries its clip radius", async () => {
  await page.click('#gallery button[data-preset="torus"]');
  await fullFrameAfter((await sentSeq()) - 1);
  await page.evaluate(() => {
    const r = document.getElementById("param-0");
    r.value = "1.85";
    r.dispatchEvent(new Event("input", { bubbles: true }));
  });
  await page.waitForFunction(() => Number(document.getElementById("bound-value").textContent) > 2.1);
  await fullFrameAfter((await sentSeq()) - 1);
  assert.ok((await canvasStats()).red > 0.03, "the torus is still there at R = 1.85");
  assert.doesNotMatch(await page.evaluate(() => window.kardia.currentScene()), /BOUND/, "the preset's own radius");
});

await check("keyboard and screen readers: focusable canvas, arrows orbit, +/− zoom, names on every control", async () => {
  await page.focus("#view");
  assert.equal(await page.evaluate(() => document.activeElement.id), "view");
  const eye = await page.evaluate(() => [...window.kardia.state.camera.eye]);
  const seq = await sentSeq();
  await page.keyboard.press("ArrowLeft");
  assert.equal(await sentSeq(), seq + 1);
  const turned = await page.evaluate(() => [...window.kardia.state.camera.eye]);
  assert.ok(Math.hypot(...turned.map((v, i) => v - eye[i])) > 0.1, "the arrow orbits");
  const distance = () => page.evaluate(() => {
    const c = window.kardia.state.camera;
    return Math.hypot(...c.eye.map((v, i) => v - c.look[i]));
  });
  const far = await distance();
  await page.keyboard.press("+");
  assert.ok((await distance()) < far * 0.95, "+ zooms in");
  await page.keyboard.press("-");
  await page.keyboard.press("-");
  assert.ok((await distance()) > far, "− zooms out");
  const unnamed = await page.evaluate(() => [...document.querySelectorAll("button, input, select, textarea, canvas")]
    .filter((e) => e.offsetParent !== null || e.id === "view")
    .filter((e) => !(e.getAttribute("aria-label") || (e.labels && e.labels.length && e.labels[0].textContent.trim())
      || e.textContent.trim() || e.title))
    .map((e) => e.id || e.outerHTML.slice(0, 60)));
  assert.deepEqual(unnamed, [], "controls without an accessible name");
  assert.equal(await page.getAttribute("#status", "aria-live"), "polite");
  await fullFrameAfter((await sentSeq()) - 1);
});

await check("Save's fields show what is saved: a width of 40000 is clamped to the limits and said", async () => {
  const size = await page.evaluate(() => [document.getElementById("view").width, document.getElementById("view").height]);
  await page.fill("#save-width", "40000");
  await page.dispatchEvent("#save-width", "change");
  assert.equal(await page.inputValue("#save-width"), "8192", "the field holds the largest side");
  assert.match(await page.textContent("#message"), /at most 8192 px a side.*: 8192×\d+ at \d+ spp is used/);
  await page.fill("#save-height", "8192");
  await page.dispatchEvent("#save-height", "change");
  const [w, h, spp] = await Promise.all(["#save-width", "#save-height", "#save-spp"].map((id) => page.inputValue(id)));
  assert.ok(Number(w) * Number(h) <= 4096 * 4096 && Number(w) * Number(h) * Number(spp) <= 2 ** 28, `${w}×${h} at ${spp}`);
  assert.deepEqual(await page.evaluate(() => [document.getElementById("view").width, document.getElementById("view").height]),
    size, "the live view keeps its size");
  await page.fill("#save-width", "80");
  await page.fill("#save-height", "60");
  await page.fill("#save-spp", "1");
  await page.dispatchEvent("#save-spp", "change");
});

await check("Save names its file after the surface and its parameters", async () => {
  await page.fill("#save-width", "80");
  await page.fill("#save-height", "60");
  await page.fill("#save-spp", "1");
  await page.evaluate(() => { window.kardia.lastPng = null; });
  await page.click("#save");
  await page.waitForFunction(() => window.kardia.lastPng, null, { timeout: 60000 });
  assert.match(await page.evaluate(() => window.kardia.lastFileName), /^kardia-torus-1\.85-0\.3\.png$/);
});

await check("Save shows its progress, can be cancelled, and never changes the live view's size", async () => {
  const size = await page.evaluate(() => [document.getElementById("view").width, document.getElementById("view").height]);
  await page.fill("#save-width", "1600");
  await page.fill("#save-height", "1200");
  await page.fill("#save-spp", "64");
  await page.evaluate(() => { window.kardia.lastPng = null; window.kardia.saveProgress = []; });
  const errors = await page.evaluate(() => window.kardia.errors.length);
  await page.click("#save");
  assert.ok(await page.isEnabled("#save-cancel"), "Cancel is offered while the save renders");
  await page.waitForFunction(() => window.kardia.saveProgress.filter((f) => f > 0).length >= 2, null, { timeout: 60000 });
  const progress = await page.evaluate(() => window.kardia.saveProgress);
  assert.ok(progress.every((f, i) => f >= 0 && f < 1 && (i === 0 || f >= progress[i - 1])), progress.join(" "));
  assert.match(await page.textContent("#message"), /rendering 1600×1200 at 64 spp: \d+ %/);
  assert.ok(Number(await page.getAttribute("#save-progress", "value")) > 0, "the bar moves");
  // The live view keeps its size and its frames while the save renders.
  const seq = await sentSeq();
  await page.focus("#view");
  await page.keyboard.press("ArrowLeft");
  await fullFrameAfter(seq);
  assert.deepEqual(await page.evaluate(() => [document.getElementById("view").width, document.getElementById("view").height]), size);
  await page.click("#save-cancel");
  await page.waitForFunction((n) => window.kardia.errors.slice(n).some((e) => /cancelled/.test(e)), errors, { timeout: 30000 });
  assert.ok(await page.isDisabled("#save-cancel"), "nothing left to cancel");
  assert.equal(await page.evaluate(() => window.kardia.lastPng), null, "no file from a cancelled save");
  // Saved again, it renders to the end.
  await page.fill("#save-width", "80");
  await page.fill("#save-height", "60");
  await page.fill("#save-spp", "1");
  await page.click("#save");
  await page.waitForFunction(() => window.kardia.lastPng, null, { timeout: 60000 });
});

await check("Save scene writes the scene text, named after the surface", async () => {
  await page.click("#copy-scene");
  const copied = await page.evaluate(() => window.kardia.clipboard);
  const download = page.waitForEvent("download");
  await page.click("#save-scene");
  const file = await download;
  assert.match(file.suggestedFilename(), /^kardia-torus-1\.85-0\.3\.scene$/);
  const saved = readFileSync(await file.path(), "utf8");
  assert.equal(saved, copied, "the file holds exactly the scene Copy scene copies");
  assert.match(saved, /^IMPLICIT /m);
});

await check("Download STL and 3MF: the same bytes as `kardia mesh` of Copy scene", async () => {
  await page.click("#copy-scene");
  const scene = await page.evaluate(() => window.kardia.clipboard);
  const dir = mkdtempSync(join(tmpdir(), "kardia-mesh-"));
  writeFileSync(join(dir, "copied.scene"), scene);
  try {
    for (const format of ["stl", "3mf"]) {
      await page.evaluate(() => { window.kardia.lastMesh = null; window.kardia.meshProgress = []; });
      const download = page.waitForEvent("download", { timeout: 180000 });
      await page.click(`#mesh-${format}`);
      const file = await download;
      assert.equal(file.suggestedFilename(), `kardia-torus-1.85-0.3.${format}`);
      assert.ok((await page.evaluate(() => window.kardia.meshProgress.length)) >= 1, "progress is reported");
      const bytes = readFileSync(await file.path());
      execFileSync(process.env.KARDIA_BIN, ["mesh", join(dir, "copied.scene"), "-o", join(dir, `cli.${format}`), "--quiet"]);
      const cli = readFileSync(join(dir, `cli.${format}`));
      assert.ok(bytes.length > 1000, `${format}: ${bytes.length} bytes`);
      assert.ok(bytes.equals(cli), `${format}: ${bytes.length} bytes from the page, ${cli.length} from kardia mesh`);
      assert.match(await page.textContent("#message"), new RegExp(`saved kardia-torus-1\\.85-0\\.3\\.${format}: \\d+ triangles`));
    }
    // Cancel mesh stops a mesh (Barth's sextic takes seconds): the page is told, nothing is
    // downloaded, and the button has nothing left to cancel.
    assert.ok(await page.isDisabled("#mesh-cancel"), "nothing to cancel before a mesh");
    await page.click('#gallery button[data-preset="barth_sextic"]');
    await fullFrameAfter((await sentSeq()) - 1);
    const errors = await page.evaluate(() => window.kardia.errors.length);
    await page.evaluate(() => { window.kardia.lastMesh = null; window.kardia.meshProgress = []; });
    await page.click("#mesh-stl");
    await page.waitForFunction(() => window.kardia.meshProgress.length >= 1, null, { timeout: 60000 });
    await page.click("#mesh-cancel");
    await page.waitForFunction((n) => window.kardia.errors.slice(n).includes("mesh cancelled"), errors, { timeout: 30000 });
    assert.ok(await page.isDisabled("#mesh-cancel"), "nothing left to cancel");
    assert.equal(await page.evaluate(() => window.kardia.lastMesh), null, "no file from a cancelled mesh");
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

await check("a burst of states over the rate limit ends on the last state", async () => {
  await page.click('#gallery button[data-preset="torus"]');
  await fullFrameAfter((await sentSeq()) - 1);
  // 300 clip radii in one go (far over the server's 200 messages a second): the server may
  // drop states in between, never the last. The burst must go out faster than the limit for
  // the check to mean anything; a loaded machine may slow the page's loop below it, so the
  // burst is tried again (up to three times) until one goes out over the limit.
  const burst = () => page.evaluate(() => {
    const start = performance.now();
    const r = document.getElementById("bound");
    for (let i = 1; i <= 300; i++) {
      r.value = String(i === 300 ? 0.93 : 1.5 + i / 100);
      r.dispatchEvent(new Event("input", { bubbles: true }));
    }
    return performance.now() - start;
  });
  let before;
  let last;
  let rate = 0;
  const rates = [];
  for (let attempt = 0; attempt < 3 && rate <= 200; attempt++) {
    before = await sentSeq();
    const took = await burst();
    last = await sentSeq();
    assert.ok(last - before >= 290, `${last - before} views sent for 300 inputs`);
    rate = ((last - before) * 1000) / took;
    rates.push(Math.round(rate));
  }
  // Over the limit: more than 200 a second (each view is a message). If the machine never let
  // the page go that fast, the rest still holds the last state, but say loudly what was missed.
  if (rate <= 200) {
    console.log(`# !!!!! no burst went out over the rate limit (${rates.join(", ")} views a second): ` +
      "the last state is checked below, the limit's dropping of states was not exercised");
  }
  await page.waitForFunction((s) => window.kardia.frames.some((f) => f.seq === s && f.width === f.view_width),
    last, { timeout: 60000 });
  const scene = await page.evaluate((s) => window.kardia.views.find((v) => v.seq === s).scene, last);
  assert.match(scene, /BOUND 0\.93\b/, "the last view sent is the final state");
  assert.deepEqual(await page.evaluate(() => window.kardia.errors.filter((e) => /too many/.test(e))), [],
    "no state the page settled on was refused");
  // And its image is the final state's: a fresh page opened on the same link draws the same pixels.
  await page.waitForFunction((s) => window.kardia.frames.some((f) => f.seq === s && f.done), last, { timeout: 120000 });
  const link = await page.evaluate(() => location.href);
  const grid = (await canvasStats()).grid;
  const fresh = await context.newPage();
  await fresh.setViewportSize(page.viewportSize());
  await fresh.goto(link);
  await fresh.waitForFunction(() => window.kardia.frames.some((f) => f.done), null, { timeout: 120000 });
  const freshGrid = await fresh.evaluate(() => {
    const c = document.getElementById("view");
    const data = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    const grid = [];
    for (let y = 0; y < 16; y++) for (let x = 0; x < 16; x++) {
      const i = (Math.floor(((y + 0.5) * c.height) / 16) * c.width + Math.floor(((x + 0.5) * c.width) / 16)) * 4;
      grid.push(data[i], data[i + 1], data[i + 2]);
    }
    return grid;
  });
  await fresh.close();
  assert.deepEqual(grid, freshGrid, "the same image as the final state's");
  // A preset slider sends two messages a step (the preset to expand, then the view): a burst
  // of them ends on the last expansion too, the equation showing the final tube radius.
  const presetBefore = await sentSeq();
  await page.evaluate(() => {
    const r = document.getElementById("param-1");
    for (let i = 1; i <= 300; i++) {
      r.value = String(i === 300 ? 0.27 : 0.1 + (i % 80) / 100);
      r.dispatchEvent(new Event("input", { bubbles: true }));
    }
  });
  assert.ok((await sentSeq()) - presetBefore >= 250, "the burst went out");
  await page.waitForFunction(() => document.getElementById("equation").value.includes("0.27^2"), null, { timeout: 30000 })
    .catch(() => {});
  assert.match(await page.inputValue("#equation"), /- 0\.27\^2\)/, "the equation is the final state's");
  assert.deepEqual(await page.evaluate(() => window.kardia.errors.filter((e) => /too many/.test(e))), [],
    "no preset the page settled on was refused");
  await page.waitForFunction((s) => window.kardia.frames.some((f) => f.seq === s && f.width === f.view_width),
    await sentSeq(), { timeout: 60000 });
});

await check("hovering the path view names that pixel's legend entry", async () => {
  await page.click('#gallery button[data-preset="heart"]');
  await page.selectOption("#study", "path");
  await fullFrameAfter((await sentSeq()) - 1);
  await page.waitForFunction(() => window.kardia.frames.some((f) => f.seq === window.kardia.sent() && f.done), null, { timeout: 120000 });
  const box = await page.locator("#view").boundingBox();
  await page.evaluate(() => { window.kardia.lastProbe = null; });
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.waitForFunction(() => window.kardia.lastProbe, null, { timeout: 20000 });
  const probe = await page.evaluate(() => window.kardia.lastProbe);
  assert.ok(probe.report && probe.report.hit, JSON.stringify(probe));
  const labels = await page.$$eval("#legend li", (l) => l.map((e) => e.dataset.label));
  assert.ok(labels.includes(probe.report.settled_by), `${probe.report.settled_by} in ${labels}`);
  assert.equal(await page.getAttribute("#legend li.probed", "data-label"), probe.report.settled_by);
  const text = await page.textContent("#probe");
  assert.ok(text.includes(probe.report.settled_by), text);
  assert.match(text, /t = [\d.]+.*distinct roots? in the interval \(degree 6\).*refinement steps?.*\|∇f\| = [\d.e-]+/);
  // The named entry's colour is the pixel's.
  const [x, y] = [probe.x, probe.y];
  const { pixel, swatch } = await page.evaluate(([x, y]) => {
    const c = document.getElementById("view");
    const p = c.getContext("2d").getImageData(x, y, 1, 1).data;
    return { pixel: [p[0], p[1], p[2]], swatch: document.querySelector("#legend li.probed .swatch").dataset.colour };
  }, [x, y]);
  const want = [1, 3, 5].map((i) => parseInt(swatch.slice(i, i + 2), 16));
  assert.ok(pixel.every((v, i) => Math.abs(v - want[i]) <= 2), `pixel ${pixel} vs ${swatch}`);
  // A pixel of the background far from the heart: no root finder reached, or a proved miss.
  await page.mouse.move(box.x + 3, box.y + 3);
  await page.waitForFunction(([x, y]) => window.kardia.lastProbe && (window.kardia.lastProbe.x !== x || window.kardia.lastProbe.y !== y),
    [x, y], { timeout: 20000 });
  assert.ok(!(await page.evaluate(() => window.kardia.lastProbe.report?.hit)), "the corner misses");
  await page.selectOption("#study", "shaded");
  await fullFrameAfter((await sentSeq()) - 1);
});

await check("an orthographic camera pans by its view height and zooms by it", async () => {
  await page.click("#mode-scene");
  const text = ["SIZE 320 240", "CAMERA (0, 0, 10) (0, 0, 0) (0, 1, 0) ORTHOGRAPHIC 4", "BACKGROUND (0.1, 0.1, 0.1)",
    "LIGHT (5, 5, 5) (1, 1, 1)", "SPHERE (0, 0, 0) 1 (0.8, 0.2, 0.2)", ""].join("\n");
  await page.fill("#scene-text", text);
  await fullFrameAfter((await sentSeq()) - 1);
  const camera = () => page.evaluate(() => structuredClone(window.kardia.state.camera));
  const start = await camera();
  assert.ok(start.orthographic, "the page reads the orthographic camera");
  const box = await page.locator("#view").boundingBox();
  const height = await page.evaluate(() => document.getElementById("view").clientHeight);
  await page.keyboard.down("Shift");
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 - 100, box.y + box.height / 2, { steps: 5 });
  await page.mouse.up();
  await page.keyboard.up("Shift");
  const panned = await camera();
  const moved = Math.hypot(...panned.look.map((v, i) => v - start.look[i]));
  // 100 pixels of a view 4 units high drawn `height` pixels high: the surface follows the pointer.
  assert.ok(Math.abs(moved - (100 * 4) / height) < 0.02 * moved, `moved ${moved}, want ${(100 * 4) / height}`);
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.wheel(0, 200);
  const zoomed = await camera();
  assert.ok(zoomed.fov > 4.5, `zooming out widens the view: height ${zoomed.fov}`);
  assert.match(await page.inputValue("#scene-text"), /ORTHOGRAPHIC [\d.]+/);
  await fullFrameAfter((await sentSeq()) - 1);
  // Its link opens the same orthographic view.
  await page.click("#copy-link");
  const link = await page.evaluate(() => window.kardia.clipboard);
  const scene = await page.evaluate(() => window.kardia.currentScene());
  const second = await context.newPage();
  second.on("pageerror", (e) => pageErrors.push("orthographic link: " + e.message));
  await second.goto(link);
  await second.waitForFunction(() => window.kardia.frames.length > 0, null, { timeout: 60000 });
  assert.equal(await second.evaluate(() => window.kardia.currentScene()), scene, "the link keeps the orthographic camera");
  await second.close();
  await page.click("#mode-equation");
  await fullFrameAfter((await sentSeq()) - 1);
});

await check("fairness: a dragging page keeps its frames beside a page saving 1600×1200 at 16 spp", async () => {
  // The dragging page is this browser's only page: a second visible page in the same
  // headless chromium slows the first one's input events to a few a second (7 mouse moves in
  // 3 s instead of 28, measured), whatever the server does.
  for (const other of context.pages()) if (other !== page) await other.close();
  const dragger = page;
  await dragger.goto("about:blank");
  await dragger.goto(`${url}#mode=equation&preset=heart&size=400x300`);
  await dragger.waitForFunction(() => window.kardia.frames.some((f) => f.width === 400 && f.done), null, { timeout: 120000 });
  const box = await dragger.locator("#view").boundingBox();
  const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
  const sent = () => dragger.evaluate(() => window.kardia.sent());
  // Drags for 3 s (a move every 16 ms): frames drawn a second, views sent a second, and the
  // time from the release to the full frame.
  const drag = async () => {
    await dragger.waitForTimeout(300);
    const before = await sent();
    await dragger.mouse.move(cx, cy);
    await dragger.mouse.down();
    const start = Date.now();
    let step = 0;
    while (Date.now() - start < 3000) {
      step += 1;
      await dragger.mouse.move(cx + 100 * Math.sin(step / 20), cy + 30 * Math.cos(step / 20));
      await dragger.waitForTimeout(16);
    }
    const seconds = (Date.now() - start) / 1000;
    const drawn = await dragger.evaluate((s) => window.kardia.frames.filter((f) => f.seq > s).length, before);
    const views = (await sent()) - before;
    const released = await dragger.evaluate(() => performance.now());
    await dragger.mouse.up();
    const last = await sent();
    await dragger.waitForFunction((s) => window.kardia.frames.some((f) => f.seq >= s && f.width === 400), last, { timeout: 120000 });
    const full = await dragger.evaluate((s) => window.kardia.frames.find((f) => f.seq >= s && f.width === 400).receivedAt, last);
    return { fps: drawn / seconds, views: views / seconds, releaseToFull: full - released };
  };
  // The target beside the save: ≥ 10 frames/s and the full frame within 300 ms of
  // release. An attempt measures it when dragging ALONE, just before, reached twice that
  // rate (≥ 20 frames/s at ≥ 10 views sent/s: the machine and this harness can deliver it
  // without the save, so the save is the only contender added). Up to 3 attempts (a drag
  // alone, then one beside a fresh save) on a noisy machine: the check passes once a
  // measurable attempt meets the target and fails if every measurable attempt misses it.
  // Only if no attempt is measurable, a floor: beside the save the page keeps at least half
  // its frames (capped at 10 a second) and gets its full frame within 1.5 s.
  const target = (beside) => beside.fps >= 10 && beside.releaseToFull <= 300;
  const floor = (alone, beside) => beside.fps >= Math.min(10, alone.fps) / 2 && beside.releaseToFull <= 1500;
  const show = (d) => `${d.fps.toFixed(1)} frames/s (${d.views.toFixed(1)} views sent/s), full frame ` +
    `${Math.round(d.releaseToFull)} ms after release`;
  const attempts = [];
  // The saving page is another person's: a browser of its own (see above).
  const otherProfile = mkdtempSync(join(tmpdir(), "kardia-chromium-"));
  const other = await chromium.launchPersistentContext(otherProfile, browserOptions);
  try {
    const saver = other.pages()[0] || (await other.newPage());
    saver.on("pageerror", (e) => pageErrors.push("saving page: " + e.message));
    await saver.goto(`${url}#mode=equation&preset=heart&size=200x150&save=1600x1200x16`);
    await saver.waitForFunction(() => window.kardia.frames.length > 0, null, { timeout: 120000 });
    for (let attempt = 1; attempt <= 3; attempt++) {
      const loadBefore = loadavg()[0];
      const alone = await drag();
      await saver.evaluate(() => {
        window.kardia.lastPng = null;
        window.kardia.saveProgress = [];
        document.getElementById("save").click();
      });
      await saver.waitForFunction(() => window.kardia.saveProgress.some((f) => f > 0), null, { timeout: 60000 });
      const beside = await drag();
      const progress = await saver.evaluate(() => window.kardia.saveProgress.at(-1));
      const finished = await saver.evaluate(() => Boolean(window.kardia.lastPng));
      // Cancelled, and its end awaited: the next attempt's drag alone is alone.
      const errors = await saver.evaluate(() => window.kardia.errors.length);
      await saver.evaluate(() => document.getElementById("save-cancel").click());
      if (!finished) {
        await saver.waitForFunction((n) => window.kardia.errors.slice(n).some((e) => /cancelled/.test(e)), errors,
          { timeout: 60000 });
      }
      const measurable = alone.fps >= 20 && alone.views >= 10;
      const result = { alone, beside, measurable, met: measurable && target(beside), finished };
      attempts.push(result);
      console.log(`# fairness attempt ${attempt} (load average ${loadBefore.toFixed(1)} → ${loadavg()[0].toFixed(1)}, ` +
        `${cpus().length} cores): dragging alone ${show(alone)}; beside the save ${show(beside)} (the save at ` +
        `${Math.round(progress * 100)} %${finished ? ", finished" : ""}); ` +
        (measurable ? (result.met ? "target met" : "target MISSED") : "not measurable (alone below 20 frames/s or 10 views sent/s)"));
      assert.ok(!finished, "the save was still rendering while the page dragged");
      if (result.met) break;
    }
  } finally {
    await other.close();
    rmSync(otherProfile, { recursive: true, force: true });
    // The page as the next checks expect it: the explorer at its defaults.
    await page.goto("about:blank");
    await page.goto(url);
    await fullFrameAfter(0);
  }
  const measured = attempts.filter((a) => a.measurable);
  if (measured.length > 0) {
    assert.ok(measured.some((a) => a.met), `every measurable attempt missed the target (≥ 10 frames/s, full frame ` +
      `≤ 300 ms beside the save): ${measured.map((a) => show(a.beside)).join("; ")}`);
  } else {
    console.log(`# !!!!! fairness target (10 frames/s, 300 ms) NOT asserted: in none of ${attempts.length} attempts ` +
      `did dragging alone reach 20 frames/s at 10 views sent/s; the floor is asserted`);
    assert.ok(attempts.some((a) => floor(a.alone, a.beside)), `the floor missed in every attempt: ` +
      attempts.map((a) => `alone ${show(a.alone)}, beside ${show(a.beside)}`).join("; "));
  }
});

await check("a hidden page pauses its refinement and resumes when shown", async () => {
  await page.click('#gallery button[data-preset="sarti"]');
  await page.waitForFunction(() => window.kardia.frames.some((f) => f.seq === window.kardia.sent() && f.spp >= 2),
    null, { timeout: 60000 });
  const setVisibility = (state) => page.evaluate((state) => {
    Object.defineProperty(document, "visibilityState", { value: state, configurable: true });
    document.dispatchEvent(new Event("visibilitychange"));
  }, state);
  await setVisibility("hidden");
  await page.waitForTimeout(300); // a frame already on its way may still arrive
  const frames = await page.evaluate(() => window.kardia.frames.length);
  await page.waitForTimeout(1500);
  assert.equal(await page.evaluate(() => window.kardia.frames.length), frames, "no frames while hidden");
  const seq = await sentSeq();
  await setVisibility("visible");
  assert.equal(await sentSeq(), seq + 1, "the view is asked for again");
  await fullFrameAfter(seq);
});

for (const [width, height] of [[390, 844], [768, 1024], [1280, 800]]) {
  await check(`at ${width}×${height}: the image fills the width on narrow screens, nothing scrolls sideways`, async () => {
    const screen = await context.newPage();
    screen.on("pageerror", (e) => pageErrors.push(`${width}: ` + e.message));
    await screen.setViewportSize({ width, height });
    await screen.goto(url);
    await screen.waitForFunction(() => window.kardia.frames.some((f) => f.width === f.view_width), null, { timeout: 60000 });
    const m = await screen.evaluate(() => ({
      scroll: document.documentElement.scrollWidth, client: document.documentElement.clientWidth,
      canvas: document.getElementById("view").getBoundingClientRect().width,
      canvasHeight: document.getElementById("view").getBoundingClientRect().height,
      status: document.getElementById("status").getBoundingClientRect().height,
    }));
    assert.ok(m.scroll <= m.client, `scrolls sideways: ${m.scroll} > ${m.client}`);
    if (width < 800) assert.ok(m.canvas >= 0.95 * width, `canvas ${m.canvas} of ${width}`);
    else assert.ok(m.canvas >= 0.6 * width, `canvas ${m.canvas} of ${width}`);
    assert.ok(m.canvasHeight >= 200, `canvas height ${m.canvasHeight}`);
    assert.ok(m.status < 60, `the status line wraps: ${m.status} px`);
    if (width === 390) {
      // Touch: one finger orbits, two fingers pinch-zoom (CDP touch events → pointer events).
      const cdp = await context.newCDPSession(screen);
      const box = await screen.locator("#view").boundingBox();
      const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
      const touch = (type, points) => cdp.send("Input.dispatchTouchEvent", {
        type, touchPoints: points.map(([x, y], id) => ({ x, y, id })),
      });
      const eye = await screen.evaluate(() => [...window.kardia.state.camera.eye]);
      await touch("touchStart", [[cx, cy]]);
      for (let i = 1; i <= 6; i++) await touch("touchMove", [[cx + 12 * i, cy]]);
      await touch("touchEnd", []);
      const turned = await screen.evaluate(() => [...window.kardia.state.camera.eye]);
      assert.ok(Math.hypot(...turned.map((v, i) => v - eye[i])) > 0.2, "a one-finger drag orbits");
      const distance = () => screen.evaluate(() => {
        const c = window.kardia.state.camera;
        return Math.hypot(...c.eye.map((v, i) => v - c.look[i]));
      });
      const before = await distance();
      await touch("touchStart", [[cx - 20, cy], [cx + 20, cy]]);
      for (let i = 1; i <= 6; i++) await touch("touchMove", [[cx - 20 - 10 * i, cy], [cx + 20 + 10 * i, cy]]);
      await touch("touchEnd", []);
      assert.ok((await distance()) < before * 0.8, `a pinch zooms in: ${before} → ${await distance()}`);
      // A typing error's sentence is whole on a phone (it wraps in its reserved space, never
      // cut short), and nothing below moves when it comes.
      const below = () => screen.evaluate(() => document.getElementById("bound").getBoundingClientRect().top);
      const top = await below();
      await screen.fill("#equation", "x^2+y^2+z^2-1+(");
      await screen.waitForFunction(() => document.getElementById("equation-problem").classList.contains("shown"),
        null, { timeout: 10000 });
      const sentence = await screen.evaluate(() => {
        const el = document.getElementById("equation-sentence");
        return { text: el.textContent, scrollW: el.scrollWidth, clientW: el.clientWidth,
          scrollH: el.scrollHeight, clientH: el.clientHeight };
      });
      assert.ok(sentence.text.length > 40, `a sentence: ${sentence.text}`);
      assert.ok(sentence.scrollW <= sentence.clientW && sentence.scrollH <= sentence.clientH,
        `the sentence is cut short on a phone: ${JSON.stringify(sentence)}`);
      assert.equal(await below(), top, "nothing moves when the error comes");
      await screen.screenshot({ path: join(tmpdir(), "kardia-phone.png") });
    }
    await screen.close();
  });
}

assert.deepEqual(pageErrors, [], "no script errors on the page");
await context.close();
rmSync(profile, { recursive: true, force: true });
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 && pageErrors.length === 0 ? 0 : 1);
