// Drives the oddball panel in headless Chromium: it must load, count down, flash with on-times
// of ON_MS (default 100 ms) within one frame, show the decisions and move the arm. Saves a
// screenshot, and one of the operator view (SCREENSHOT-operator.png), which must list the
// decisions with their confidence. With GAP_MS, every flash of a trial must be scheduled ON_MS
// on and GAP_MS off (the `fast` timing: 100 and 75; the off-time within 2 ms, as onsets fall on
// EEG samples), and the measured gap between the frame
// that took a flash off and the one that drew the next must be within one frame of GAP_MS.
//
//   node panel.mjs URL OPERATOR_URL SCREENSHOT.png N_DECISIONS [ON_MS [GAP_MS]]
//
// URL and OPERATOR_URL: the session's `panel:` and `operator view:` lines (each with its key).
//
// Chromium: $CHROMIUM or /usr/bin/chromium (Debian's). Prints one JSON line of measurements;
// exits 1 with the reasons when a check fails.
import { chromium } from "playwright-core";

const [url, operatorUrl, shot, nDecisions, onArg, gapArg] = process.argv.slice(2);
const onMs = onArg === undefined ? 100 : Number(onArg);
const gapMs = gapArg === undefined ? null : Number(gapArg);
if (!url || !operatorUrl || !shot || !nDecisions) {
  console.error("usage: node panel.mjs URL OPERATOR_URL SCREENSHOT.png N_DECISIONS");
  process.exit(2);
}
const want = Number(nDecisions);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-background-timer-throttling", "--disable-renderer-backgrounding"],
});
let failures = [];
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 760 } });
  page.on("console", (m) => { if (m.type() === "error") console.error("page:", m.text()); });
  page.on("pageerror", (e) => failures.push(`page error: ${e.message}`));
  await page.goto(url);
  // The countdown shows a digit before the first flash.
  await page.waitForFunction(() => /^[1-5]$/.test(document.getElementById("count").textContent), null, { timeout: 30000 });
  // A rogue second client: malformed, oversized and binary messages and an abort on the
  // subject's socket, then it just goes away. Without the key it is refused at the door
  // (and with it, as a second subject view, closed unheard): the session carries on.
  await page.waitForFunction(() => window.oddballDiag.flashes >= 2, null, { timeout: 30000 });
  const rogue = await page.evaluate(() => {
    const attempt = (query) => new Promise((done) => {
      const ws = new WebSocket(`ws://${location.host}/ws${query}`);
      let closedBy = null;
      ws.onopen = () => {
        ws.send("{not json");
        ws.send(JSON.stringify({ t: "hello", frame_ms: 16, agent: "x".repeat(4000) }));
        ws.send(new Uint8Array([1, 2, 3]));
        ws.send(JSON.stringify({ t: "on", id: 1, code: 99, on_ms: 0 }));
        // Only the operator view may abort: on the subject's socket this is refused.
        ws.send(JSON.stringify({ t: "control", action: "abort" }));
      };
      ws.onclose = (ev) => { closedBy = ev.code; done(closedBy); };
      // Time enough for a handshake on a loaded machine (closing it while it connects reads
      // as 1006, not the server's 4409).
      setTimeout(() => { ws.close(); done(closedBy); }, 5000);
    });
    // Without the key (refused at the door), then with the page's own key (a second subject
    // view: closed by the server, 4409, unheard).
    return Promise.all([attempt(""), attempt(location.search)]);
  });
  if (rogue[1] !== 4409) failures.push(`a second subject socket was not closed by the server: ${JSON.stringify(rogue)}`);
  const operator = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  operator.on("pageerror", (e) => failures.push(`operator page error: ${e.message}`));
  await operator.goto(operatorUrl);
  await page.waitForFunction((n) => window.oddballDiag.decisions.length >= n, want, { timeout: 60000 * want, polling: 200 });
  // Let the arm move after the last decision.
  await page.waitForTimeout(1500);
  await page.screenshot({ path: shot });
  await operator.waitForFunction((n) => window.oddballOperator.decisions >= n, want, { timeout: 10000 });
  await operator.screenshot({ path: shot.replace(/\.png$/, "-operator.png"), fullPage: true });
  const rows = await operator.evaluate(() => [...document.querySelectorAll("#decisions tr")].map((tr) => [...tr.cells].map((c) => c.textContent)));
  const confidences = rows.map((r) => Number(r[3]));
  if (rows.length !== want || !confidences.every((p) => p >= 0 && p <= 1)) failures.push(`operator decisions: ${JSON.stringify(rows)}`);
  const d = await page.evaluate(() => window.oddballDiag);
  const frame = d.frameMs;
  const on = d.onTimes;
  const err = d.onsetErrors;
  const worstOn = Math.max(...on.map((x) => Math.abs(x - onMs)));
  // Successive flashes of one trial (scheduled less than half a second apart): scheduled and
  // measured off-times between them.
  const drawn = [...d.drawn].sort((a, b) => a.at - b.at);
  const gaps = [];
  for (let i = 1; i < drawn.length; i++) {
    const [a, b] = [drawn[i - 1], drawn[i]];
    const nominal = b.at - (a.at + a.dur);
    if (nominal < 500) gaps.push({ nominal, measured: b.on - a.off });
  }
  const gapNominal = gaps.map((g) => g.nominal), gapMeasured = gaps.map((g) => g.measured);
  const worstGap = gapMs === null ? null : Math.max(...gapMeasured.map((x) => Math.abs(x - gapMs)));
  const out = {
    frame_ms: frame, flashes: d.flashes, countdowns: d.countdowns, decisions: d.decisions.length,
    decided: d.decisions.map((x) => [x.intended, x.code]),
    on_ms_nominal: onMs, on_ms_min: Math.min(...on), on_ms_max: Math.max(...on), on_ms_worst_error: worstOn,
    on_ms_scheduled: [...new Set(drawn.map((f) => f.dur))],
    gap_ms_nominal: gapMs, gaps: gaps.length, gap_ms_scheduled: [...new Set(gapNominal.map((x) => Math.round(x * 100) / 100))],
    gap_ms_min: Math.min(...gapMeasured), gap_ms_max: Math.max(...gapMeasured), gap_ms_worst_error: worstGap,
    onset_error_ms_min: Math.min(...err), onset_error_ms_max: Math.max(...err),
    clock_rtt_ms: d.rtt, arm_moves: d.armMoves, cancelled: d.cancelled,
    targets: d.targets, plan_points: d.planPoints, ended: d.ended, late_flashes: d.lateFlashes,
    operator_decisions: rows,
  };
  console.log(JSON.stringify(out));
  if (d.countdowns < want) failures.push(`only ${d.countdowns} countdowns`);
  if (d.flashes < 4 * want) failures.push(`only ${d.flashes} flashes drawn`);
  if (!(worstOn <= frame)) failures.push(`flash on-time off ${onMs} ms by ${worstOn.toFixed(2)} ms (> one frame, ${frame.toFixed(2)} ms)`);
  if (!drawn.every((f) => Math.abs(f.dur - onMs) < 0.5)) failures.push(`flashes scheduled ${JSON.stringify(out.on_ms_scheduled)} ms on, not ${onMs}`);
  if (gapMs !== null) {
    if (gaps.length < 4 * want - 2) failures.push(`only ${gaps.length} gaps between the flashes of a trial`);
    // Onsets are scheduled on the EEG's sample clock (2 ms at the simulator's 500 Hz), so a
    // 175 ms pitch is 176 or 174 ms: the schedule must hold GAP_MS within 2 ms.
    if (!gapNominal.every((g) => Math.abs(g - gapMs) <= 2)) failures.push(`gaps scheduled ${JSON.stringify(out.gap_ms_scheduled)} ms, not ${gapMs}`);
    if (!(worstGap <= frame)) failures.push(`gap between flashes off ${gapMs} ms by ${worstGap.toFixed(2)} ms (> one frame, ${frame.toFixed(2)} ms)`);
  }
  // Onsets land on the frame nearest the schedule; a busy machine may miss frames, so only
  // gross errors fail (the figures are printed above).
  if (!(Math.max(...err.map(Math.abs)) <= 3 * frame)) failures.push(`flash onset off schedule by up to ${Math.max(...err.map(Math.abs)).toFixed(2)} ms (> three frames)`);
  if (d.decisions.length < want) failures.push(`${d.decisions.length} decisions shown, expected ${want}`);
  if (d.armMoves < 1) failures.push("the arm never moved on the page");
} catch (e) {
  failures.push(String(e));
} finally {
  await browser.close();
}
if (failures.length) {
  console.error("panel test failed:\n  " + failures.join("\n  "));
  process.exit(1);
}
