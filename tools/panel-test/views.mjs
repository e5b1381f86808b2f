// Drives both of oddball's pages in headless Chromium: the subject view full screen and the
// operator view beside it. Checks that the subject view fills the screen and shows no operator
// figures, that the operator view shows calibration progress and channel quality, that a pause
// stops the flashing (none drawn while paused) and a resume restarts it, and that abort ends
// the session (both pages told). Saves two screenshots.
//
//   node views.mjs URL SUBJECT.png OPERATOR.png [CHANNELS]
//
// CHANNELS, a JSON object such as {"ch0":"ok","ch1":"flat or saturated"}: the state the
// operator view must show for each channel after the first trial.
// URL is the subject view (the session's `panel:` line), OPERATOR_URL the operator view (its
// `operator view:` line); each carries its view's key.
// Chromium: $CHROMIUM or /usr/bin/chromium. Prints one JSON line of what it saw; exits 1 with
// the reasons when a check fails. Also saves each view paused (-paused.png) and at the end
// (-end.png) beside the two screenshots.
import { chromium } from "playwright-core";

const [url, operatorUrl, subjectShot, operatorShot, channelsJson] = process.argv.slice(2);
if (!url || !operatorUrl || !subjectShot || !operatorShot) {
  console.error("usage: node views.mjs URL OPERATOR_URL SUBJECT.png OPERATOR.png");
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
  const subject = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  const operator = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  for (const [name, p] of [["subject", subject], ["operator", operator]]) {
    p.on("console", (m) => { if (m.type() === "error") console.error(`${name}:`, m.text()); });
    p.on("pageerror", (e) => failures.push(`${name} page error: ${e.message}`));
  }
  // The operator view first: the session must still wait for the subject view.
  await operator.goto(operatorUrl);
  await operator.waitForFunction(() => window.oddballOperator.connected, null, { timeout: 10000 });
  await sleep(1500);
  out.started_without_subject = await operator.evaluate(() => window.oddballOperator.number);
  if (out.started_without_subject !== 0) failures.push("the session started with only the operator view open");

  await subject.goto(url);
  // Full screen on the F key (a trusted gesture).
  await subject.keyboard.press("f");
  await subject.waitForFunction(() => window.oddballDiag.connected, null, { timeout: 10000 });
  out.fullscreen = await subject.evaluate(() => window.oddballDiag.fullscreen);
  if (!out.fullscreen) failures.push("the subject view did not go full screen on F");

  // Calibration trial 2 under way: the quality table has the first trial's channels.
  await operator.waitForFunction(() => {
    const o = window.oddballOperator;
    return o.phase === "calibration" && o.number >= 2 && o.channels.length > 0;
  }, null, { timeout: 60000, polling: 100 });
  await subject.waitForFunction(() => window.oddballDiag.flashes >= 6, null, { timeout: 30000, polling: 50 });
  // Catch a frame with a bulb lit, for a picture of the task as the person sees it.
  await subject.waitForFunction(() => document.querySelector(".bulb.on") !== null, null, { timeout: 10000, polling: "raf" });
  await subject.screenshot({ path: subjectShot });
  const layout = await subject.evaluate(() => {
    const r = (id) => document.getElementById(id).getBoundingClientRect();
    const text = document.body.innerText;
    return {
      vw: innerWidth, vh: innerHeight, grid: [r("grid").width, r("grid").height], arm: [r("arm").width, r("arm").height],
      text,
      operator_words: ["offset", "rtt", "onset", "on-time", "calibrat", "undrawn", "ms"].filter((w) => text.toLowerCase().includes(w)),
    };
  });
  out.layout = { vw: layout.vw, vh: layout.vh, grid: layout.grid, arm: layout.arm, operator_words: layout.operator_words };
  if (layout.grid[1] < 0.85 * layout.vh) failures.push(`the bulbs take ${layout.grid[1]} of ${layout.vh} px of height`);
  if (layout.arm[0] < 0.25 * layout.vw || layout.arm[1] < 0.6 * layout.vh) failures.push(`the arm is ${layout.arm} px in a ${layout.vw}×${layout.vh} view`);
  if (layout.operator_words.length) failures.push(`the subject view shows operator figures: ${layout.operator_words} in ${JSON.stringify(layout.text)}`);

  const op = await operator.evaluate(() => ({
    state: document.getElementById("state").textContent,
    o: window.oddballOperator,
    diag: document.getElementById("diag").textContent,
  }));
  await operator.screenshot({ path: operatorShot, fullPage: true });
  out.operator_state = op.state;
  out.channels = op.o.channels.map((c) => c.name);
  if (!/^calibration: decision \d+ of \d+$/.test(op.state)) failures.push(`operator progress reads ${JSON.stringify(op.state)}`);
  if (!op.o.of) failures.push("no calibration total");
  out.channel_states = await operator.evaluate(() => Object.fromEntries(
    [...document.querySelectorAll("#channels tr")].map((tr) => [tr.cells[0].textContent, tr.cells[1].textContent])));
  if (channelsJson) {
    const want = JSON.parse(channelsJson);
    for (const [name, state] of Object.entries(want)) {
      if (out.channel_states[name] !== state) failures.push(`channel ${name} shows ${JSON.stringify(out.channel_states[name])}, expected ${JSON.stringify(state)}`);
    }
  }
  if (!/flash on-time/.test(op.diag) || !/page clock offset/.test(op.diag)) failures.push(`no flash timing or clock on the operator view: ${op.diag}`);
  if (op.o.subjectPages !== 1) failures.push(`the operator view counts ${op.o.subjectPages} subject views`);

  // Pause: the trial under way finishes, then nothing flashes until Resume.
  await operator.click("#pause");
  await subject.waitForFunction(() => window.oddballDiag.paused, null, { timeout: 60000, polling: 50 });
  await operator.waitForFunction(() => window.oddballOperator.paused, null, { timeout: 5000 });
  // Quality is per trial and in all: two trials in, a dead channel's total exceeds its last.
  const dead = await operator.evaluate(() => window.oddballOperator.channels.map((c) => [c.name, c.last.flat, c.total.flat]));
  out.flat_last_total = dead;
  if (channelsJson && !dead.some(([, last, total]) => last > 0 && total > last)) failures.push(`flat counts per trial and in all: ${JSON.stringify(dead)}`);
  const before = await subject.evaluate(() => window.oddballDiag.flashes);
  await sleep(3000);
  const during = await subject.evaluate(() => window.oddballDiag.flashes);
  out.paused_at_flash = before; out.flashes_while_paused = during - before;
  out.overlay = await subject.evaluate(() => document.getElementById("overlay").textContent);
  out.paused_state = await operator.evaluate(() => document.getElementById("state").textContent);
  await subject.screenshot({ path: subjectShot.replace(/\.png$/, "-paused.png") });
  await operator.screenshot({ path: operatorShot.replace(/\.png$/, "-paused.png"), fullPage: true });
  if (during !== before) failures.push(`${during - before} flashes drawn while paused`);
  if (!/paused/i.test(out.overlay)) failures.push(`the subject view does not say it is paused: ${out.overlay}`);
  await operator.click("#resume");
  await subject.waitForFunction((n) => window.oddballDiag.flashes >= n + 4, before, { timeout: 30000, polling: 50 });
  out.resumed = await subject.evaluate(() => ({ paused: window.oddballDiag.paused, flashes: window.oddballDiag.flashes }));
  if (out.resumed.paused) failures.push("still paused after resume");

  // Abort takes two clicks; both pages hear that the session is over.
  await operator.click("#abort");
  await operator.click("#abort");
  await subject.waitForFunction(() => window.oddballDiag.ended, null, { timeout: 30000, polling: 50 });
  await operator.waitForFunction(() => window.oddballOperator.ended, null, { timeout: 10000 });
  out.end_text = await subject.evaluate(() => document.getElementById("center").innerText);
  await subject.waitForTimeout(300);
  await subject.screenshot({ path: subjectShot.replace(/\.png$/, "-end.png") });
  await operator.screenshot({ path: operatorShot.replace(/\.png$/, "-end.png"), fullPage: true });
  out.end_state = await operator.evaluate(() => [document.getElementById("state").textContent, document.getElementById("progress-line").textContent]);
  if (!/session over/i.test(out.end_text)) failures.push(`the subject view does not say the session is over: ${out.end_text}`);
  const after = await subject.evaluate(() => document.body.innerText);
  if (/calibrat/i.test(after)) failures.push(`the subject view still speaks of calibration: ${JSON.stringify(after)}`);
  console.log(JSON.stringify(out));
} catch (e) {
  failures.push(String(e));
  console.log(JSON.stringify(out));
} finally {
  await browser.close();
}
if (failures.length) {
  console.error("views test failed:\n  " + failures.join("\n  "));
  process.exit(1);
}
