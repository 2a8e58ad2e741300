// The screenshots of docs/explorer.md (a script, not a test): the desktop (1280×800) on
// Togliatti's quintic and a phone (390×844) on the heart, as a new user first sees them
// (shaded), each once its view has refined to 16 samples a pixel or more, then rewritten as
// indexed-colour PNGs (`cargo run --release --example png_palette`: 272 KB -> 108 KB for
// the desktop, the text as legible).
//
// Usage: node tests/browser/screenshots.mjs URL DIR
//   (URL: a running `kardia explore`; DIR: where explorer_desktop.png and explorer_phone.png go)
import { chromium } from "playwright-core";
import { mkdtempSync, rmSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { tmpdir } from "node:os";
import { join } from "node:path";

const [url, dir] = process.argv.slice(2);
if (!url || !dir) throw new Error("usage: node tests/browser/screenshots.mjs URL DIR");
const profile = mkdtempSync(join(tmpdir(), "kardia-chromium-"));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
const refined = (page) => page.waitForFunction(() => window.kardia.frames.some(
  (f) => f.seq === window.kardia.sent() && f.width === f.view_width && f.spp >= 16), null, { timeout: 300000 });
try {
  const desktop = context.pages()[0] || (await context.newPage());
  await desktop.setViewportSize({ width: 1280, height: 800 });
  await desktop.goto(`${url}#mode=equation&preset=togliatti`);
  await refined(desktop);
  await desktop.waitForFunction(() => [...document.querySelectorAll("#gallery img")].every((i) => i.complete), null,
    { timeout: 300000 });
  await desktop.screenshot({ path: join(dir, "explorer_desktop.png") });
  const phone = await context.newPage();
  await phone.setViewportSize({ width: 390, height: 844 });
  await phone.goto(`${url}#mode=equation&preset=heart`);
  await refined(phone);
  await phone.screenshot({ path: join(dir, "explorer_phone.png") });
  for (const name of ["explorer_desktop.png", "explorer_phone.png"]) {
    execFileSync("cargo", ["run", "--quiet", "--release", "--example", "png_palette", "--",
      join(dir, name), join(dir, name)], { stdio: "inherit" });
  }
} finally {
  await context.close();
  rmSync(profile, { recursive: true, force: true });
}
