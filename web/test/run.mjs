// Drives the browser viewer in headless Chromium with WebGPU on
// SwiftShader, and writes what it saw to OUT_DIR for scripts/web.sh test:
//   page.exr     the traced image (linear mean radiance), read back by the page
//   result.json  its size and samples, the speed, the panel, the drop test
//   shot.png     a screenshot of the page
// Usage: node run.mjs URL OUT_DIR BAD_SCENE_FILE
// Fails (exit 1) when the page does not render or misreports.

import { chromium } from "playwright-core";
import { readFileSync, writeFileSync } from "node:fs";
import { basename, join } from "node:path";

const [url, outDir, badScene] = process.argv.slice(2);
if (!url || !outDir || !badScene) {
  console.error("usage: node run.mjs URL OUT_DIR BAD_SCENE_FILE");
  process.exit(2);
}
const fail = (why) => {
  console.error(`web test: ${why}`);
  process.exit(1);
};

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  args: [
    "--headless=new",
    "--no-sandbox",
    "--enable-unsafe-webgpu",
    "--use-webgpu-adapter=swiftshader",
    "--enable-unsafe-swiftshader",
    // The compositor on SwiftShader's Vulkan too: without these, headless
    // Chromium cannot share the WebGPU canvas's swap chain images with the
    // compositor, and the GPU process drops the page's WebGPU instance.
    "--enable-features=Vulkan",
    "--use-vulkan=swiftshader",
    "--use-angle=swiftshader",
  ],
});
try {
  const page = await browser.newPage({ viewport: { width: 640, height: 360 } });
  const log = [];
  page.on("console", (m) => log.push(`console.${m.type()}: ${m.text()}`));
  page.on("pageerror", (e) => log.push(`page error: ${e.message}`));
  const spp = Number(process.env.PT_WEB_SPP ?? 64);
  await page.goto(`${url}?test&spp=${spp}&per_frame=4`);

  // The traced image, once the asked samples are in (or the page's own
  // explanation of why it cannot trace).
  try {
    await page.waitForFunction(() => window.ptTest || window.ptError, null, { timeout: 600_000, polling: 500 });
  } catch (e) {
    fail(`no image: ${e.message}\n${log.join("\n")}`);
  }
  const error = await page.evaluate(() => window.ptError);
  if (error) fail(`the page says: ${error}\n${log.join("\n")}`);
  const test = await page.evaluate(() => {
    const t = window.ptTest;
    let binary = "";
    for (let i = 0; i < t.exr.length; i += 0x8000) {
      binary += String.fromCharCode(...t.exr.subarray(i, i + 0x8000));
    }
    return { ...t, exr: btoa(binary) };
  });
  writeFileSync(join(outDir, "page.exr"), Buffer.from(test.exr, "base64"));
  const before = await page.evaluate(() => window.ptState);

  // A bad scene file dropped on the canvas: the page must show the error
  // and keep the scene it has.
  const name = basename(badScene);
  const text = readFileSync(badScene, "utf8");
  const drop = await page.evaluateHandle(
    ([name, text]) => {
      const dt = new DataTransfer();
      dt.items.add(new File([text], name, { type: "text/plain" }));
      return dt;
    },
    [name, text],
  );
  for (const type of ["dragenter", "dragover", "drop"]) {
    await page.dispatchEvent("#pt-canvas", type, { dataTransfer: drop });
  }
  await page.waitForFunction((s) => window.ptState.status !== s, before.status, { timeout: 60_000 });
  const after = await page.evaluate(() => window.ptState);

  await page.screenshot({ path: join(outDir, "shot.png") });

  // A browser without WebGPU: the page must say so, not show a blank canvas.
  const bare = await browser.newPage({ viewport: { width: 640, height: 360 } });
  await bare.addInitScript(() => delete Navigator.prototype.gpu);
  await bare.goto(url);
  await bare.waitForFunction(() => window.ptError, null, { timeout: 60_000 });
  const noWebGpu = await bare.evaluate(() => ({
    message: window.ptError,
    shown: getComputedStyle(document.getElementById("pt-message")).display !== "none",
    canvasHidden: getComputedStyle(document.getElementById("pt-canvas")).display === "none",
  }));
  if (!noWebGpu.shown || !noWebGpu.canvasHidden || !noWebGpu.message.includes("no WebGPU")) {
    fail(`without WebGPU the page shows ${JSON.stringify(noWebGpu)}`);
  }
  const result = {
    width: test.width,
    height: test.height,
    spp: test.spp,
    tracedMs: test.tracedMs,
    samplesPerSecond: test.samplesPerSecond,
    adapter: test.adapter,
    panelWidth: test.panelWidth,
    dropStatus: after.status,
    sceneKept: after.scene === before.scene,
    noWebGpuMessage: noWebGpu.message,
    userAgent: await page.evaluate(() => navigator.userAgent),
  };
  writeFileSync(join(outDir, "result.json"), JSON.stringify(result, null, 2) + "\n");
  console.log(JSON.stringify(result, null, 2));
} finally {
  await browser.close();
}
