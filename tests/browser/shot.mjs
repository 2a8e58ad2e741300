import { chromium } from "playwright-core";
import { mkdtempSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
const url = process.argv[2], out = process.argv[3];
const ctx = await chromium.launchPersistentContext(mkdtempSync(join(tmpdir(), "kardia-")), {
  executablePath: "/usr/bin/chromium", headless: true,
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  viewport: { width: 1200, height: 760 },
});
const page = ctx.pages()[0] || await ctx.newPage();
page.on("console", (m) => console.log("console:", m.text()));
page.on("pageerror", (e) => console.log("pageerror:", e.message));
await page.goto(url);
await page.waitForTimeout(Number(process.argv[4] || 4000));
await page.screenshot({ path: out });
console.log(JSON.stringify(await page.evaluate(() => window.kardia.frames.slice(-3))));
await ctx.close();
