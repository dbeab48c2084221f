// Drives the real Foxglove Studio 1.48 (npm @foxglove/studio-base, served by serve.mjs through studio/index.html)
// in headless Debian Chromium through puppeteer-core, and reports what a person would see, as JSON lines on
// stdout; tests/browser/test_studio.py starts the session, judges the report and keeps the screenshots.
//
//   node studio.mjs CONFIG.json
//
// CONFIG: {chromium, out (screenshot folder), layout (layout file), layout_fbg (the layout for sessions with FBG
// sensors), fault_wait_s, ee_rgb and ee_fault_rgb ([r, g, b] 0..255 of the end effector, normal and in FAULT),
// timeout_s}. One JSON line {"stage": ...} per
// stage: "ready" (Studio loaded with no data source, while the session starts), then per line on stdin, each
// opening Studio again in the same page on a deep link (studio/host.js's studioOpen: no reload of the build):
//   live WS_URL ROBOT_PID   -> "live" (Studio's foxglove-websocket deep link with the layout: the sidebar, every
//                              panel's text twice 2.5 s apart, pixels changed between two screenshots and the
//                              end effector's colour per panel), then "fault" (ROBOT_PID paused with SIGSTOP
//                              until a log panel shows a FAULT line, at most fault_wait_s; the log panels)
//   recording PATH [ISO]    -> "recording" (the same page opening PATH through Studio's remote-file source, at
//                              time ISO if given (Studio's `time` deep link): its topic list and problems)
//   live-fbg WS_URL         -> "live_fbg" (as "live", with layout_fbg and no fault: a session with FBG sensors;
//                              screenshots live-fbg-1.png, live-fbg.png)
// and "done" when stdin ends (the console errors and the server's 404s).
import { mkdtempSync, readFileSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { createInterface } from "node:readline";

import puppeteer from "puppeteer-core";

import { serve } from "./serve.mjs";

const cfg = JSON.parse(readFileSync(process.argv[2], "utf8"));
const T0 = Date.now();
const elapsed = () => (Date.now() - T0) / 1000;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const emit = (obj) => process.stdout.write(JSON.stringify({ ...obj, elapsed_s: elapsed() }) + "\n");
const stdinLines = createInterface({ input: process.stdin });

const panelIdsOf = (file) => Object.keys(JSON.parse(readFileSync(file, "utf8")).configById);
const panelIds = panelIdsOf(cfg.layout);
const files = { "layout.json": cfg.layout };
if (cfg.layout_fbg) files["layout-fbg.json"] = cfg.layout_fbg;

/** Every panel of the layout (`ids`: its panels; the main layout's by default): its type, whether it is mounted,
 *  its text and its box on the page. */
async function panels(page, ids = panelIds) {
  return page.evaluate((ids) => {
    const out = {};
    for (const id of ids) {
      const el = document.querySelector(`[data-testid="panel-mouseenter-container ${id}"]`);
      const r = el?.getBoundingClientRect();
      out[id] = {
        type: id.split("!")[0], found: !!el, text: el ? el.innerText : "",
        box: r ? { x: r.x, y: r.y, width: r.width, height: r.height } : null,
      };
    }
    return out;
  }, ids);
}

/** What two screenshots (PNG buffers, one taken after the other) show inside each panel's box: `changed`
 *  pixels, of which `changed_colour` are colourful (a plotted series, a state bar; not grey text or grid), and
 *  `ee` pixels of the colour `rgb` in the second (a lit or shaded surface of it: the same chromaticity at some
 *  brightness). Decoded in the page itself (an <img> drawn on a 2D canvas): no image library needed. */
async function pixels(page, pngA, pngB, boxes, rgb) {
  return page.evaluate(async (a64, b64, boxes, rgb) => {
    const decode = async (b64) => {
      const img = new Image();
      img.src = `data:image/png;base64,${b64}`;
      await img.decode();
      const c = document.createElement("canvas");
      c.width = img.width;
      c.height = img.height;
      const g = c.getContext("2d");
      g.drawImage(img, 0, 0);
      return g.getImageData(0, 0, img.width, img.height);
    };
    const A = await decode(a64);
    const B = await decode(b64);
    const norm = Math.hypot(...rgb);
    const unit = rgb.map((v) => v / norm);
    const out = {};
    for (const [id, box] of Object.entries(boxes)) {
      if (!box) continue;
      const x0 = Math.max(0, Math.floor(box.x)), y0 = Math.max(0, Math.floor(box.y));
      const x1 = Math.min(B.width, Math.floor(box.x + box.width));
      const y1 = Math.min(B.height, Math.floor(box.y + box.height));
      let changed = 0, changedColour = 0, ee = 0, ex = 0, ey = 0;
      for (let y = y0; y < y1; y++) {
        for (let x = x0; x < x1; x++) {
          const i = 4 * (y * B.width + x);
          const p = [B.data[i], B.data[i + 1], B.data[i + 2]];
          const diff = Math.abs(p[0] - A.data[i]) + Math.abs(p[1] - A.data[i + 1]) + Math.abs(p[2] - A.data[i + 2]);
          if (diff > 60) {
            changed++;
            const q = [A.data[i], A.data[i + 1], A.data[i + 2]];
            if (Math.max(...p) - Math.min(...p) > 80 || Math.max(...q) - Math.min(...q) > 80) changedColour++;
          }
          const len = Math.hypot(...p);
          if (len >= 60 && (p[0] * unit[0] + p[1] * unit[1] + p[2] * unit[2]) / len > 0.985) {
            ee++;
            ex += x;
            ey += y;
          }
        }
      }
      out[id] = { changed, changed_colour: changedColour, ee, ee_centre: ee ? [ex / ee, ey / ee] : null,
        box: { x: x0, y: y0, width: x1 - x0, height: y1 - y0 } };
    }
    return out;
  }, pngA.toString("base64"), pngB.toString("base64"), boxes, rgb);
}

const boxes = (ps) => Object.fromEntries(Object.entries(ps).map(([id, p]) => [id, p.box]));

/** The data source sidebar's text (source, start time, duration and the open tab: Topics or Problems). */
async function sidebar(page, tab) {
  await page.evaluate((tab) => {
    [...document.querySelectorAll("button[role=tab]")].find((b) => b.innerText.startsWith(tab))?.click();
  }, tab);
  await sleep(400);
  return page.evaluate(() => {
    let el = [...document.querySelectorAll("[role=tablist]")].find((t) => t.innerText.includes("Problems"));
    while (el && !/DURATION/.test(el.innerText)) el = el.parentElement;
    return el ? el.innerText : "";
  });
}

async function waitFor(what, fn, timeoutMs) {
  const until = Date.now() + timeoutMs;
  let last;
  while (Date.now() < until) {
    last = await fn();
    if (last.ok) return last;
    await sleep(500);
  }
  return { ...last, timedOut: what };
}

/** Studio on the deep link `url` (the host page's own URL with Studio's parameters), in the page already loaded. */
async function open(page, url) {
  await page.evaluate((search) => window.studioOpen(search), new URL(url).search.slice(1));
}

/** Studio on `host` (its layout) connected to the session at `ws`: once data shows in every panel of `ids`, the
 *  panels' text twice 2.5 s apart and the pixels changed between two screenshots (`shot`-1.png, `shot`.png). */
async function watch(page, host, timeout, ws, ids, shot) {
  const asked = elapsed();
  await open(page, `${host}&ds=foxglove-websocket&ds.url=${encodeURIComponent(ws)}`);
  const loaded = elapsed();
  const connected = await waitFor("data in every panel", async () => {
    const ps = await panels(page, ids);
    const info = await sidebar(page, "Problems");
    // connected: the server's name beside its URL and a start time (Studio 1.48's websocket player takes it from
    // its own clock; it read 0 in two runs on a loaded machine, with every panel receiving)
    const ok = /START TIME\s*\n\s*\d/.test(info) && info.includes("cdpr-teleop") &&
      Object.values(ps).every((p) => p.found) &&
      !Object.values(ps).some((p) => /Waiting for next message/.test(p.text));
    return { ok, info };
  }, timeout);
  const shown = elapsed();
  await sleep(1000);
  const first = await panels(page, ids);
  const shotA = await page.screenshot({ path: join(cfg.out, `${shot}-1.png`) });
  await sleep(2500); // the 1 Hz panels (timing, stats) have news twice over; plots and the time axes move on
  const second = await panels(page, ids);
  const shotB = await page.screenshot({ path: join(cfg.out, `${shot}.png`) });
  return {
    report: {
      connected: !connected.timedOut, asked_s: asked, loaded_s: loaded, shown_s: shown,
      sidebar: await sidebar(page, "Problems"), first, second,
      pixels: await pixels(page, shotA, shotB, boxes(second), cfg.ee_rgb),
      host_error: await page.evaluate(() => window.hostError ?? null),
    },
    shotB,
  };
}

async function live(page, host, timeout, ws, robotPid) {
  const { report, shotB } = await watch(page, host, timeout, ws, panelIds, "live");
  emit({ stage: "live", ...report });

  // an induced fault: the robot process paused until the log panel shows the fault (the loop, slower than real
  // time on a loaded machine, takes its staleness limit in its own ticks), then let go
  process.kill(robotPid, "SIGSTOP");
  let faulted;
  try {
    faulted = await waitFor("a FAULT line in the log panel", async () => {
      const logs = Object.entries(await panels(page)).filter(([, p]) => p.type === "RosOut" || p.type === "Log");
      return { ok: logs.some(([, p]) => /-> FAULT/.test(p.text)), logs: Object.fromEntries(logs) };
    }, cfg.fault_wait_s * 1000);
  } finally {
    process.kill(robotPid, "SIGCONT");
  }
  const ps = await panels(page);
  const shotF = await page.screenshot({ path: join(cfg.out, "fault.png") });
  emit({ stage: "fault", found: !faulted.timedOut, log_panels: faulted.logs, sidebar: await sidebar(page, "Problems"),
    pixels: await pixels(page, shotB, shotF, boxes(ps), cfg.ee_fault_rgb) });
}

async function recording(page, host, timeout, path, endIso) {
  files["session.mcap"] = path;
  const time = endIso ? `&time=${encodeURIComponent(endIso)}` : "";
  const url = `${origin}/files/session.mcap`;
  await open(page, `${host}&ds=remote-file&ds.url=${encodeURIComponent(url)}${time}`);
  const opened = await waitFor("the recording's duration shown", async () => {
    const info = await sidebar(page, "Topics");
    return { ok: /DURATION\s*\n\s*\d+:\d\d:\d\d/.test(info), info };
  }, timeout);
  await sleep(500);
  const topics = await sidebar(page, "Topics");
  await page.screenshot({ path: join(cfg.out, "recording.png") });
  const problems = await sidebar(page, "Problems");
  await page.screenshot({ path: join(cfg.out, "recording-problems.png") });
  emit({ stage: "recording", opened: !opened.timedOut, topics, sidebar: problems, panels: await panels(page) });
}

async function liveFbg(page, origin, timeout, ws) {
  const host = `${origin}/studio/index.html?layoutId=teleop-fbg&layout=/files/layout-fbg.json`;
  const { report } = await watch(page, host, timeout, ws, panelIdsOf(cfg.layout_fbg), "live-fbg");
  emit({ stage: "live_fbg", ...report });
}

const THREE_D = panelIds.find((id) => id.startsWith("3D!"));
const NOBOX = { x: 0, y: 0, width: 0, height: 0 };
const profile = mkdtempSync(join(tmpdir(), "studio-profile-"));
const { server, origin, log: httpLog } = await serve(files);
const browser = await puppeteer.launch({
  executablePath: cfg.chromium,
  headless: true,
  userDataDir: profile,
  // WebGL (the 3D panel) on the CPU: Chromium 156 still falls back to SwiftShader by itself and says that this
  // is deprecated; the page is our own, so the fallback is asked for by name
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--enable-unsafe-swiftshader"],
  defaultViewport: { width: 1600, height: 1000 },
  handleSIGTERM: false,
});
// stopped from outside (the test's clean-up): the browser, in its own process group, goes too
process.once("SIGTERM", () => {
  browser.process()?.kill("SIGKILL");
  setTimeout(() => {
    rmSync(profile, { recursive: true, force: true });
    process.exit(143);
  }, 500);
});
const consoleErrors = [];
try {
  const timeout = (cfg.timeout_s ?? 40) * 1000;
  const host = `${origin}/studio/index.html?layoutId=teleop&layout=/files/layout.json`;
  // while the session starts: Studio's build loaded and shown with no data source
  const page = await browser.newPage();
  page.on("console", (m) => { if (m.type() === "error") consoleErrors.push(m.text().slice(0, 500)); });
  page.on("pageerror", (e) => consoleErrors.push(`pageerror: ${String(e).slice(0, 500)}`));
  await page.goto(host, { timeout });
  await page.waitForFunction(() => window.hostReady || window.hostError, { timeout });
  emit({ stage: "ready", host_error: await page.evaluate(() => window.hostError ?? null) });
  for await (const line of stdinLines) {
    const [cmd, ...args] = line.trim().split(" ");
    if (cmd === "live") await live(page, host, timeout, args[0], Number(args[1]));
    else if (cmd === "recording") await recording(page, host, timeout, args[0], args[1]);
    else if (cmd === "live-fbg") await liveFbg(page, origin, timeout, args[0]);
    else break;
  }
  emit({ stage: "done", console_errors: consoleErrors, http_404: httpLog });
} finally {
  await browser.close();
  server.close();
  rmSync(profile, { recursive: true, force: true });
}
process.exit(0);
