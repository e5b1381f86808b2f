// A subject tab sent to the background during a live calibration, in headless Chromium: the
// page is made to believe it is hidden (document.hidden, a visibilitychange event) and its
// frames are throttled to one a second, as a browser does to a background tab, for as long as
// the check needs; then it comes back. Checks that the operator view raises an alarm naming
// the fault and when, that the calibration holds (no trial starts, nothing is announced) while
// the tab is hidden and goes on by itself once it is back, and that the session ends. Saves
// screenshots of the operator view with the alarm on, and of both views at the end.
//
//   node throttle.mjs URL OPERATOR_URL SHOT_PREFIX
//
// SHOT_PREFIX: e.g. target/panel-throttle, giving -alarm.png, -subject.png, -operator.png.
// Chromium: $CHROMIUM or /usr/bin/chromium. Prints one JSON line of what it saw (the operator
// view's presentation-fault counts among it); exits 1 with the reasons when a check fails.
import { chromium } from "playwright-core";

const [url, operatorUrl, prefix] = process.argv.slice(2);
if (!url || !operatorUrl || !prefix) {
  console.error("usage: node throttle.mjs URL OPERATOR_URL SHOT_PREFIX");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-background-timer-throttling", "--disable-renderer-backgrounding",
         "--disable-backgrounding-occluded-windows"],
});
const failures = [];
const out = {};
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
try {
  const operator = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const subject = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  for (const [name, p] of [["subject", subject], ["operator", operator]]) {
    p.on("console", (m) => { if (m.type() === "error") console.error(`${name}:`, m.text()); });
    p.on("pageerror", (e) => failures.push(`${name} page error: ${e.message}`));
  }
  await operator.goto(operatorUrl);
  await subject.goto(url);
  // Calibration trial 2 flashing.
  await operator.waitForFunction(() => window.oddballOperator.phase === "calibration" && window.oddballOperator.number >= 2,
    null, { timeout: 60000, polling: 100 });
  await subject.waitForFunction(() => document.querySelector(".bulb.on") !== null, null, { timeout: 20000, polling: "raf" });
  out.hidden_in_trial = await operator.evaluate(() => window.oddballOperator.number);

  // To the background: hidden, and one frame a second.
  await subject.evaluate(() => {
    window.__raf = window.requestAnimationFrame;
    Object.defineProperty(document, "hidden", { configurable: true, get: () => true });
    Object.defineProperty(document, "visibilityState", { configurable: true, get: () => "hidden" });
    window.requestAnimationFrame = (cb) => setTimeout(() => window.__raf.call(window, cb), 1000);
    document.dispatchEvent(new Event("visibilitychange"));
  });
  const t0 = Date.now();
  // The alarm, at once, naming the fault and when.
  await operator.waitForFunction(() => window.oddballOperator.alarms.some((a) => a.kind === "hidden" && a.active),
    null, { timeout: 5000, polling: 50 });
  out.alarm_after_ms = Date.now() - t0;
  out.banner = await operator.evaluate(() => document.getElementById("alarm-banner").innerText);
  if (!/subject view hidden/i.test(out.banner) || !/since \d{1,2}:\d\d:\d\d/.test(out.banner)) {
    failures.push(`the alarm banner does not name the fault and when: ${JSON.stringify(out.banner)}`);
  }
  // The trial under way finishes; then calibration holds for the hidden tab.
  await operator.waitForFunction(() => window.oddballOperator.heldFor === "hidden", null, { timeout: 20000, polling: 50 });
  const held = await operator.evaluate(() => ({
    number: window.oddballOperator.number, state: document.getElementById("state").textContent,
    line: document.getElementById("progress-line").textContent,
  }));
  const sub0 = await subject.evaluate(() => ({ flashes: window.oddballDiag.flashes, skipped: window.oddballDiag.skipped }));
  await operator.screenshot({ path: `${prefix}-alarm.png`, fullPage: true });
  await sleep(3000);
  const sub1 = await subject.evaluate(() => ({ flashes: window.oddballDiag.flashes, skipped: window.oddballDiag.skipped }));
  out.held = { ...held, hidden_for_ms: Date.now() - t0,
    number_after_3s: await operator.evaluate(() => window.oddballOperator.number),
    flashes_while_held: sub1.flashes - sub0.flashes, announced_while_held: sub1.skipped - sub0.skipped };
  if (out.held.number_after_3s !== held.number) failures.push(`a trial started while the subject tab was hidden: ${JSON.stringify(out.held)}`);
  if (out.held.flashes_while_held || out.held.announced_while_held) failures.push(`flashes announced while held: ${JSON.stringify(out.held)}`);
  if (!/^held after calibration/.test(held.state)) failures.push(`the operator state reads ${JSON.stringify(held.state)}`);
  out.skipped_hidden = await subject.evaluate(() => window.oddballDiag.skippedHidden);

  // Back to the front: the calibration goes on by itself.
  await subject.evaluate(() => {
    delete document.hidden;
    delete document.visibilityState;
    window.requestAnimationFrame = window.__raf;
    document.dispatchEvent(new Event("visibilitychange"));
  });
  await operator.waitForFunction((n) => window.oddballOperator.number > n && !window.oddballOperator.paused,
    held.number, { timeout: 20000, polling: 50 });
  out.alarm_over = await operator.evaluate(() => window.oddballOperator.alarms
    .filter((a) => a.kind === "hidden").map((a) => ({ active: a.active, seconds: a.seconds, when: a.when })));
  if (!out.alarm_over.length || out.alarm_over.some((a) => a.active)) failures.push(`the hidden alarm did not end: ${JSON.stringify(out.alarm_over)}`);
  // A picture of the task as the person sees it, a bulb lit.
  await subject.waitForFunction(() => document.querySelector(".bulb.on") !== null, null, { timeout: 20000, polling: "raf" });
  await subject.screenshot({ path: `${prefix}-subject-flash.png` });

  // The session runs to its end (two decisions).
  await operator.waitForFunction(() => window.oddballOperator.ended, null, { timeout: 120000, polling: 200 });
  await subject.waitForTimeout(500);
  await subject.screenshot({ path: `${prefix}-subject.png` });
  await operator.screenshot({ path: `${prefix}-operator.png`, fullPage: true });
  const o = await operator.evaluate(() => window.oddballOperator);
  out.faults = o.faults;
  out.alarms = o.alarms.map((a) => ({ kind: a.kind, active: a.active, count: a.count, text: a.text, when: a.when }));
  out.held_trials = o.heldTrials;
  out.signal_messages = o.signalMessages;
  out.states = o.states;
  out.average = o.average && { trial: o.average.trial, target: o.average.target, n_target: o.average.n_target, n_other: o.average.n_other };
  out.decisions = o.decisions;
  out.subject = await subject.evaluate(() => {
    const d = window.oddballDiag;
    return { flashes: d.flashes, skipped: d.skipped, skipped_hidden: d.skippedHidden, multi_lit: d.multiLit, view: d.view };
  });
  if (!o.faults || !(o.faults.calibration_undrawn_flashes > 0)) failures.push(`no undrawn calibration flash counted: ${JSON.stringify(o.faults)}`);
  if (!(o.faults && o.faults.hidden >= 1 && o.faults.calibration_holds >= 1)) failures.push(`faults: ${JSON.stringify(o.faults)}`);
  if (!(o.signalMessages > 50)) failures.push(`only ${o.signalMessages} signal messages`);
  if (!o.average || !o.average.target_uv.length) failures.push("no average of the last trial");
  if (out.subject.multi_lit) failures.push(`${out.subject.multi_lit} frames with more than one bulb lit`);
  console.log(JSON.stringify(out));
} catch (e) {
  failures.push(String(e));
  console.log(JSON.stringify(out));
} finally {
  await browser.close();
}
if (failures.length) {
  console.error("throttle test failed:\n  " + failures.join("\n  "));
  process.exit(1);
}
