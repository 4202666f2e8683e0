// Opens a generated report and viewer in headless Chromium (playwright-core driving the
// system's /usr/bin/chromium; Playwright's own browser download is never used) and
// prints what it saw as one JSON object on stdout. It judges nothing: the Rust test
// `tests/report_browser.rs` asserts on these facts, so all the rules live in one place.
//
//   node web/tests/browser.mjs --report R.html --view V.html --shots DIR [--sweep-report S.html] [--chromium PATH]
//
// Pages are opened from file:// with every http(s)/ws request aborted and recorded, so a
// page that needs the network shows up as a blocked request, not as a silent success.

import { chromium } from "playwright-core";
import { mkdirSync } from "node:fs";
import { join, resolve } from "node:path";
import { pathToFileURL } from "node:url";
import { parseArgs } from "node:util";

const { values: args } = parseArgs({
  options: {
    report: { type: "string" },
    view: { type: "string" },
    "sweep-report": { type: "string" },
    shots: { type: "string" },
    chromium: { type: "string", default: "/usr/bin/chromium" },
  },
});
if (!args.report || !args.view || !args.shots) {
  console.error("usage: browser.mjs --report R.html --view V.html --shots DIR [--chromium PATH]");
  process.exit(2);
}
mkdirSync(args.shots, { recursive: true });

const browser = await chromium.launch({
  executablePath: args.chromium,
  headless: true,
  args: [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    // WebGL without a GPU: ANGLE on SwiftShader, Chromium's software renderer.
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
  ],
});

/** A page that records console errors, uncaught exceptions and network requests. */
async function open(file, viewport) {
  const context = await browser.newContext({ viewport, deviceScaleFactor: 1 });
  const page = await context.newPage();
  const seen = { console_errors: [], page_errors: [], blocked_requests: [] };
  page.on("console", (m) => {
    if (m.type() === "error") seen.console_errors.push(m.text());
  });
  page.on("pageerror", (e) => seen.page_errors.push(String(e)));
  await context.route(
    (url) => !["file:", "data:", "blob:"].includes(url.protocol),
    (route) => {
      seen.blocked_requests.push(route.request().url());
      return route.abort();
    },
  );
  await page.goto(pathToFileURL(resolve(file)).href, { waitUntil: "load" });
  return { page, seen, context };
}

/** Two animation frames: whatever the last input changed has been drawn. */
const settle = (page) =>
  page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

/** Pixels (of the same size) that differ between two PNGs, decoded by the browser. */
async function differingPixels(page, a, b) {
  return page.evaluate(
    async ([a, b]) => {
      const decode = async (b64) => {
        const img = new Image();
        img.src = `data:image/png;base64,${b64}`;
        await img.decode();
        const c = document.createElement("canvas");
        c.width = img.width;
        c.height = img.height;
        const ctx = c.getContext("2d");
        ctx.drawImage(img, 0, 0);
        return ctx.getImageData(0, 0, c.width, c.height);
      };
      const [x, y] = await Promise.all([decode(a), decode(b)]);
      if (x.width !== y.width || x.height !== y.height) return { differing: -1, total: 0 };
      let n = 0;
      for (let i = 0; i < x.data.length; i += 4) {
        const d =
          Math.abs(x.data[i] - y.data[i]) +
          Math.abs(x.data[i + 1] - y.data[i + 1]) +
          Math.abs(x.data[i + 2] - y.data[i + 2]);
        if (d > 24) n += 1;
      }
      return { differing: n, total: x.width * x.height };
    },
    [a.toString("base64"), b.toString("base64")],
  );
}

/** Per canvas id: present, its size, and how many pixels hold paint (alpha > 0). */
async function canvases(page, ids) {
  return page.evaluate((ids) => {
    return ids.map((id) => {
      const el = document.getElementById(id);
      if (!el) return { id, exists: false };
      const out = { id, exists: true, tag: el.tagName.toLowerCase(), width: el.width, height: el.height };
      if (out.tag === "canvas" && el.width > 0 && el.height > 0) {
        const pixels = el.getContext("2d").getImageData(0, 0, el.width, el.height).data;
        let painted = 0;
        for (let i = 3; i < pixels.length; i += 4) if (pixels[i] > 0) painted += 1;
        out.painted_pixels = painted;
      }
      return out;
    });
  }, ids);
}

const result = {};

// --- the report (and a sweep's report, the same page with the sweep's curves) --------
async function checkReport(file, shot) {
  const { page, seen, context } = await open(file, { width: 1400, height: 900 });
  await page.waitForFunction(() => window.thorarenaReport?.ready === true, null, { timeout: 20000 }).catch(() => {});
  const state = await page.evaluate(() => window.thorarenaReport ?? null);
  const declared = await page.evaluate(() => JSON.parse(document.getElementById("report-data").textContent).plots);
  const tables = await page.evaluate(() =>
    Object.fromEntries(
      [...document.querySelectorAll("table[id]")].map((t) => [t.id, t.querySelectorAll("tbody tr").length]),
    ),
  );
  const facts = {
    ...seen,
    ready: state?.ready === true,
    declared_plots: declared,
    points: state?.points ?? {},
    plots: await canvases(page, declared),
    tables,
    warning_box: await page.locator("#comparability-warnings").count(),
    title: await page.title(),
    // Per chart, as Chart.js holds it: each dataset's policy, colours, dash and marker, and
    // each legend entry as drawn (null when the page exposes no charts).
    charts: await page.evaluate(() => window.thorarenaCharts ?? null),
  };
  await page.screenshot({ path: join(args.shots, shot), fullPage: true });
  await context.close();
  return facts;
}
result.report = await checkReport(args.report, "report.png");
if (args["sweep-report"]) result.sweep_report = await checkReport(args["sweep-report"], "sweep-report.png");

// --- the viewer ---------------------------------------------------------------------------
{
  const { page, seen, context } = await open(args.view, { width: 1280, height: 800 });
  await page.waitForFunction(() => window.thorarenaView?.ready === true, null, { timeout: 20000 }).catch(() => {});
  const state = await page.evaluate(() => {
    const v = window.thorarenaView;
    return v ? { ready: v.ready, steps: v.steps, bodies: v.bodies, shapes: v.shapes, ghost: v.ghost } : null;
  });
  const view = { ...seen, ...(state ?? { ready: false }) };
  if (state?.ready) {
    const sceneShot = async (name) => {
      await settle(page);
      return page.locator("#scene").screenshot({ path: join(args.shots, name) });
    };
    const later = Math.floor((state.steps - 1) * 0.6);
    // Everything visible at two times, for people looking at the artifacts.
    const full = await sceneShot("view-start.png");
    await page.locator("#timeline").fill(String(later));
    await sceneShot("view-later.png");
    // The robot alone against the empty scene, at the start and later on.
    await page.locator("#timeline").fill("0");
    for (const id of ["#show-reference", "#show-forces", "#show-robot"]) await page.locator(id).uncheck();
    await page.locator("#follow").uncheck();
    const empty = await sceneShot("view-empty.png");
    await page.locator("#show-robot").check();
    const robotStart = await sceneShot("view-robot-start.png");
    await page.locator("#timeline").fill(String(later));
    const robotLater = await sceneShot("view-robot-later.png");
    view.step_after_fill = await page.evaluate(() => window.thorarenaView.step);
    view.later_step = later;
    view.robot_vs_empty = await differingPixels(page, empty, robotStart);
    view.robot_start_vs_later = await differingPixels(page, robotStart, robotLater);
    view.full_vs_empty = await differingPixels(page, empty, full);
    view.plot = (await canvases(page, ["kp-error-plot"]))[0];
    view.foot_plot = (await canvases(page, ["foot-slip-plot"]))[0];
    view.feet = await page.evaluate(() => window.thorarenaView.feet);
    view.foot_plot_datasets = await page.evaluate(() => window.thorarenaView.footPlot);
    // Play runs the timeline by itself.
    await page.locator("#timeline").fill("0");
    await page.locator("#play").click();
    await page.waitForTimeout(800);
    view.step_after_play = await page.evaluate(() => window.thorarenaView.step);
    await page.locator("#play").click();
    view.time_label = await page.locator("#time-label").textContent();
  }
  result.view = view;
  await page.screenshot({ path: join(args.shots, "view-page.png") });
  await context.close();
}

await browser.close();
process.stdout.write(`${JSON.stringify(result, null, 2)}\n`);
