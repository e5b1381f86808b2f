// oddball operator view: progress, presentation alarms, the signal (a scrolling trace per
// channel and the last trial's averages), signal quality, decisions, flash timing; pause,
// resume and abort. It never draws or stamps flashes (the subject view at / does).
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const S = { config: null, trial: null, paused: false, pauseAsked: false, ended: null, fault: null };
  // What tests can read.
  const O = (window.oddballOperator = {
    connected: false, phase: null, number: 0, of: null, paused: false, ended: false,
    decisions: 0, channels: [], controls: [], subjectPages: 0,
    // Presentation faults: every alarm episode (kind, since, active, text), the counts, the
    // fault a calibration holds for; the signal display's channels, messages and states; the
    // last average.
    alarms: [], faults: null, heldFor: null, heldTrials: [],
    scope: null, signalMessages: 0, states: [], average: null,
  });
  const FAULT_NAMES = {
    disconnected: "no subject view", hidden: "subject view hidden", stalled: "subject view not drawing",
    undrawn: "flashes not drawn", late: "flashes late", frame_gap: "frames missed",
    multiple_lit: "several bulbs lit",
  };

  const conn = Oddball.connect(ODDBALL_WS.operator, {
    open() { O.connected = true; $("conn").textContent = "connected"; },
    message: onMessage,
    close(ended) {
      O.connected = false;
      $("conn").textContent = ended ? "session over" : "disconnected — retrying";
    },
  });

  function control(action) {
    conn.send({ t: "control", action });
    O.controls.push(action);
  }
  $("pause").onclick = () => {
    control("pause");
    S.pauseAsked = true;
    showState();
  };
  $("resume").onclick = () => {
    control("resume");
    S.pauseAsked = false;
    showState();
  };
  // Abort takes a second click within 4 s (no modal dialog to block the page).
  let armedUntil = 0;
  $("abort").onclick = () => {
    const now = performance.now();
    if (now > armedUntil) {
      armedUntil = now + 4000;
      $("abort").textContent = "Abort: click again";
      $("abort").classList.add("armed");
      setTimeout(() => { if (performance.now() >= armedUntil) { $("abort").textContent = "Abort"; $("abort").classList.remove("armed"); } }, 4100);
      return;
    }
    control("abort");
    $("abort").textContent = "aborting…";
    $("abort").disabled = true;
  };

  function showState() {
    const t = S.trial;
    let state, line = "", frac = 0;
    // Trials done: every decision shown; in calibration, the trials before this one.
    if (t && t.of) frac = (t.phase === "online" ? O.decisions : t.number - 1) / t.of;
    if (S.ended !== null) {
      state = "session over";
      line = S.ended;
    } else if (!t) {
      state = "waiting for the first trial";
    } else {
      const what = t.phase === "calibration" ? "calibration" : "online";
      const of = t.of !== null ? ` of ${t.of}` : "";
      state = `${what}: decision ${t.number}${of}`;
      if (S.paused && S.fault) {
        state = `held after ${state}`;
        line = `${FAULT_NAMES[S.fault] || S.fault}: calibration goes on by itself once the subject view draws again`;
      } else if (S.paused) { state = `paused after ${state}`; line = "nothing flashes until Resume"; }
      else if (S.pauseAsked) line = "pausing after the decision under way…";
      else line = t.phase === "calibration" ? "cued decisions: the model learns from them" : "decisions drive the arm";
    }
    $("state").textContent = state;
    $("state").className = S.ended !== null ? "over" : (S.paused ? "paused" : "");
    $("progress-line").textContent = line;
    $("progress").value = frac;
    const over = S.ended !== null;
    $("pause").disabled = over || (S.paused && !S.fault) || S.pauseAsked;
    $("resume").disabled = over || !((S.paused && !S.fault) || S.pauseAsked);
    if (over) {
      $("abort").disabled = true;
      if (O.controls.includes("abort")) $("abort").textContent = "aborted";
    }
  }

  function cell(tr, text, cls) {
    const td = document.createElement("td");
    td.textContent = text;
    if (cls) td.className = cls;
    tr.appendChild(td);
  }

  function onMessage(m) {
    switch (m.t) {
      case "config":
        S.config = m;
        $("title").textContent = m.title;
        break;
      case "trial":
        // A new trial starts, so the previous one's calibration count is done.
        S.trial = m;
        O.phase = m.phase; O.number = m.number; O.of = m.of;
        if (S.paused) { S.paused = false; O.paused = false; S.fault = null; }
        showState();
        break;
      case "paused":
        S.paused = m.paused; O.paused = m.paused;
        S.fault = m.paused ? (m.fault || null) : null; O.heldFor = S.fault;
        if (S.fault) O.heldTrials.push({ fault: S.fault, number: O.number, at_ms: m.at_ms });
        if (!m.paused) S.pauseAsked = false;
        showState();
        break;
      case "alarm": alarm(m); break;
      case "faults": faults(m.counts); break;
      case "scope": scope(m); break;
      case "signal": signal(m); break;
      case "average": average(m); break;
      case "decision": {
        O.decisions++;
        const tr = document.createElement("tr");
        const cued = m.intended === null ? "–" : Oddball.label(S.config, m.intended);
        const decided = Oddball.label(S.config, m.code);
        const cls = m.code === null ? "none" : (m.intended === null ? "" : (m.intended === m.code ? "right" : "wrong"));
        cell(tr, String(m.trial));
        cell(tr, cued);
        cell(tr, decided + (cls === "right" ? " ✓" : cls === "wrong" ? " ✗" : ""), cls);
        cell(tr, m.confidence.toFixed(3));
        cell(tr, String(m.rounds));
        cell(tr, m.refused ? `arm refused: ${m.refused}` : "");
        $("decisions").prepend(tr);
        break;
      }
      case "quality": {
        O.channels = m.channels;
        const body = $("channels");
        body.textContent = "";
        for (const c of m.channels) {
          const tr = document.createElement("tr");
          const l = c.last;
          const [state, cls] = l.non_finite > 0 ? ["samples lost (NaN)", "q-nan"]
            : l.flat > 0 ? ["flat or saturated", "q-flat"]
            : l.over_threshold > 0 ? ["noisy", "q-noisy"] : ["ok", "q-ok"];
          cell(tr, c.name);
          cell(tr, state, cls);
          cell(tr, `${l.non_finite} / ${c.total.non_finite}`);
          cell(tr, `${l.flat} / ${c.total.flat}`);
          cell(tr, `${l.over_threshold} / ${c.total.over_threshold}`);
          body.appendChild(tr);
        }
        break;
      }
      case "diag": $("diag").textContent = m.text; break;
      case "pages":
        O.subjectPages = m.subject;
        $("pages").textContent = (m.subject > 0 ? `subject view open (${m.subject})` : "no subject view open!") +
          (m.refused_subjects > 0 ? ` — ALARM: ${m.refused_subjects} other subject view(s) refused (a stale tab or a stranger: only the first one stamps flashes)` : "");
        $("pages").className = m.subject > 0 && !(m.refused_subjects > 0) ? "q-ok" : "q-flat";
        break;
      case "end":
        S.ended = m.summary; O.ended = true;
        showState();
        break;
    }
  }
  // ---- Presentation alarms -------------------------------------------------------------
  // A session-clock time as the wall clock of this page and as time into the session.
  function when(m, ms) {
    const wall = new Date(m.since_unix_ms + (ms - m.since_ms));
    const s = Math.max(0, ms / 1000);
    const mmss = `${Math.floor(s / 60)}:${String(Math.floor(s % 60)).padStart(2, "0")}`;
    return `${wall.toLocaleTimeString([], { hour12: false })} (session ${mmss})`;
  }
  function alarm(m) {
    let e = O.alarms.find((a) => a.kind === m.kind && a.since_ms === m.since_ms);
    if (!e) { e = { kind: m.kind, since_ms: m.since_ms }; O.alarms.push(e); }
    Object.assign(e, { active: m.active, last_ms: m.last_ms, count: m.count, text: m.text, holds: m.holds,
                       when: when(m, m.since_ms), seconds: (m.last_ms - m.since_ms) / 1000 });
    if (O.alarms.length > 300) O.alarms.shift();
    showAlarms();
  }
  function showAlarms() {
    const active = O.alarms.filter((a) => a.active);
    const banner = $("alarm-banner");
    banner.textContent = "";
    for (const a of active) {
      const div = document.createElement("div");
      div.className = "item";
      const b = document.createElement("b");
      b.textContent = `⚠ ${FAULT_NAMES[a.kind] || a.kind}`;
      div.appendChild(b);
      div.appendChild(document.createTextNode(` since ${a.when}: ${a.text}`));
      banner.appendChild(div);
    }
    const on = active.length > 0;
    if (on !== banner.classList.contains("on")) banner.classList.toggle("on", on);
    const body = $("alarms");
    body.textContent = "";
    for (const a of [...O.alarms].reverse().slice(0, 100)) {
      const tr = document.createElement("tr");
      if (a.active) tr.className = "active";
      cell(tr, a.when);
      cell(tr, FAULT_NAMES[a.kind] || a.kind);
      const lasted = a.seconds >= 0.05 ? ` — ${a.active ? "for" : "lasted"} ${a.seconds.toFixed(1)} s` : "";
      cell(tr, a.text + lasted + (a.active ? "" : " (over)"));
      body.appendChild(tr);
    }
    if (!O.alarms.length) {
      const tr = document.createElement("tr");
      cell(tr, "none so far", "none"); tr.cells[0].colSpan = 3;
      body.appendChild(tr);
    }
  }
  function faults(c) {
    O.faults = c;
    const parts = [];
    if (c.undrawn_flashes) parts.push(`${c.undrawn_flashes} flashes not drawn (${c.calibration_undrawn_flashes} in calibration: no epoch)`);
    if (c.late_flashes) parts.push(`${c.late_flashes} late`);
    if (c.hidden) parts.push(`hidden ${c.hidden}× (${c.hidden_s.toFixed(1)} s)`);
    if (c.stalled) parts.push(`not drawing ${c.stalled}× (${c.stalled_s.toFixed(1)} s)`);
    if (c.disconnected) parts.push(`no subject view ${c.disconnected}× (${c.disconnected_s.toFixed(1)} s)`);
    if (c.frame_gaps) parts.push(`${c.frame_gaps} frame gaps (longest ${c.longest_frame_gap_ms.toFixed(0)} ms)`);
    if (c.multiple_lit_frames) parts.push(`${c.multiple_lit_frames} frames with several bulbs lit`);
    if (c.calibration_holds) parts.push(`calibration held ${c.calibration_holds}× (${c.calibration_held_s.toFixed(1)} s)`);
    $("faults-line").textContent = "presentation: " + (parts.length ? parts.join(", ") : "no fault");
    $("faults-line").className = parts.length ? "bad" : "";
  }

  // ---- The signal ----------------------------------------------------------------------
  const WINDOW_S = 10;
  const STATE_STYLE = {
    ok: ["#cfd8dc", "ok"], flat: ["#e57373", "flat or saturated"], noisy: ["#ffb74d", "noisy"],
    nan: ["#ce93d8", "samples lost"],
  };
  const T = { names: [], bin: 20, n: 500, lo: [], hi: [], next: null, count: 0, state: [], dirty: false };
  function scope(m) {
    O.scope = m;
    T.names = m.names; T.bin = m.bin_ms; T.n = Math.round(WINDOW_S * 1000 / m.bin_ms);
    T.lo = m.names.map(() => new Float32Array(T.n).fill(NaN));
    T.hi = m.names.map(() => new Float32Array(T.n).fill(NaN));
    T.count = 0; T.next = null; T.state = m.names.map(() => "ok");
    $("band").textContent = `band-passed ${m.band} as the decoder sees it; flat under ${m.flat_uv} µV, noisy over ${m.noisy_uv === null ? "–" : m.noisy_uv + " µV"} peak-to-peak`;
    T.dirty = true;
  }
  // Bins go into a ring (slot = bin number modulo the window): a gap in time leaves empty bins.
  function signal(m) {
    if (!T.names.length) return;
    O.signalMessages++;
    const k = m.lo[0] ? m.lo[0].length : 0;
    let first = Math.round(m.t_ms / T.bin);
    if (T.next !== null && first > T.next) {
      for (let b = T.next; b < Math.min(first, T.next + T.n); b++) {
        for (let c = 0; c < T.names.length; c++) { T.lo[c][b % T.n] = NaN; T.hi[c][b % T.n] = NaN; }
      }
    }
    for (let j = 0; j < k; j++) {
      const slot = ((first + j) % T.n + T.n) % T.n;
      for (let c = 0; c < T.names.length; c++) { T.lo[c][slot] = m.lo[c][j]; T.hi[c][slot] = m.hi[c][j]; }
    }
    T.next = first + k;
    T.state = m.state; O.states = m.state;
    const bad = m.state.map((s, c) => [T.names[c], s]).filter(([, s]) => s !== "ok");
    $("signal-state").textContent = bad.length ? bad.map(([n, s]) => `${n}: ${STATE_STYLE[s][1]}`).join(", ") : "all channels ok";
    $("signal-state").style.color = bad.length ? "#ffb74d" : "#81c784";
    T.dirty = true;
  }
  $("scale").onchange = () => { T.dirty = true; A.dirty = true; };
  function fit(c) {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    return [c.getContext("2d"), w, h, dpr];
  }
  function drawTraces() {
    const [g, w, h, dpr] = fit($("traces"));
    g.clearRect(0, 0, w, h);
    const n = T.names.length;
    if (!n) return;
    const uvPerDiv = Number($("scale").value);
    const left = 92 * dpr, right = 16 * dpr, bottom = 18 * dpr;
    const row = (h - bottom) / n;
    const px = (w - left - right) / T.n;
    g.font = `${12 * dpr}px system-ui, sans-serif`;
    g.textBaseline = "middle";
    // Seconds back from now.
    g.strokeStyle = "#262626"; g.lineWidth = 1; g.fillStyle = "#777"; g.textAlign = "center";
    for (let s = 0; s < WINDOW_S; s += 1) {
      const x = w - right - s * 1000 / T.bin * px;
      g.beginPath(); g.moveTo(x, 0); g.lineTo(x, h - bottom); g.stroke();
      g.textAlign = s ? "center" : "right";
      g.fillText(s ? `−${s} s` : "now", s ? x : w, h - bottom / 2);
    }
    for (let c = 0; c < n; c++) {
      const mid = row * (c + 0.5);
      const [color, word] = STATE_STYLE[T.state[c]] || STATE_STYLE.ok;
      g.textAlign = "left"; g.fillStyle = color;
      g.fillText(T.names[c], 6 * dpr, mid - 7 * dpr);
      g.fillStyle = T.state[c] === "ok" ? "#666" : color;
      g.font = `${10 * dpr}px system-ui, sans-serif`;
      g.fillText(word, 6 * dpr, mid + 8 * dpr);
      g.font = `${12 * dpr}px system-ui, sans-serif`;
      g.strokeStyle = "#1f1f1f"; g.beginPath(); g.moveTo(left, mid); g.lineTo(w - right, mid); g.stroke();
      // One division is a channel's row; a trace is clipped at its row's edges (a noisy
      // channel does not hide its neighbours: it shows as a full band).
      const y = (v) => mid - Math.max(-0.48, Math.min(0.48, v / uvPerDiv)) * row;
      g.strokeStyle = color; g.lineWidth = Math.max(1, dpr); g.beginPath();
      if (T.next === null) continue;
      let prev = null;
      for (let i = 0; i < T.n; i++) {
        const slot = ((T.next - T.n + i) % T.n + T.n) % T.n;
        const lo = T.lo[c][slot], hi = T.hi[c][slot];
        if (Number.isNaN(lo) || Number.isNaN(hi)) { prev = null; continue; }
        const x = left + (i + 0.5) * px;
        const a = prev === null ? lo : Math.min(lo, prev[1]), b = prev === null ? hi : Math.max(hi, prev[0]);
        g.moveTo(x, y(a)); g.lineTo(x, y(b) - 0.5);
        prev = [lo, hi];
      }
      g.stroke();
    }
    // The scale: one division, a bar the height of a row.
    g.strokeStyle = "#888"; g.lineWidth = 2 * dpr;
    g.beginPath(); g.moveTo(w - 7 * dpr, 2); g.lineTo(w - 7 * dpr, row - 2); g.stroke();
  }

  // ---- The last trial's averages -------------------------------------------------------
  const A = { m: null, dirty: false };
  function average(m) {
    A.m = m; O.average = m; A.dirty = true;
    const label = m.target === null ? "none" : `${Oddball.ARROWS[Oddball.label(S.config, m.target)] || ""} ${Oddball.label(S.config, m.target)}`;
    const which = `${m.phase} decision ${m.trial}`;
    $("erp-title").textContent = m.target === null
      ? `last trial's average, ${which}: its ${m.n_other} flashes`
      : `last trial's average, ${which}: ${label} (${m.n_target} flashes, blue) against the others (${m.n_other}, grey)`;
  }
  function drawAverages() {
    const [g, w, h, dpr] = fit($("erp"));
    g.clearRect(0, 0, w, h);
    const m = A.m;
    if (!m || !O.scope) return;
    const n = O.scope.names.length;
    const lines = [...m.other_uv, ...m.target_uv];
    const len = Math.max(2, ...lines.map((l) => l.length));
    // One scale for all channels, set by those in a good state now (a noisy channel would
    // flatten the others); a channel beyond it is clipped.
    const ok = (c) => (O.states[c] || "ok") === "ok";
    const good = [...m.other_uv.filter((_, c) => ok(c)), ...m.target_uv.filter((_, c) => ok(c))];
    const peak = Math.max(1, ...(good.length ? good : lines).flat().map(Math.abs));
    const cols = n > 4 ? 2 : 1, rows = Math.ceil(n / cols);
    const cw = w / cols, ch = h / rows;
    const t0 = O.scope.erp_tmin_ms, dt = O.scope.erp_dt_ms;
    g.font = `${11 * dpr}px system-ui, sans-serif`; g.textBaseline = "top";
    for (let c = 0; c < n; c++) {
      const ox = (c % cols) * cw, oy = Math.floor(c / cols) * ch;
      const pad = 4 * dpr, mid = oy + ch / 2;
      const X = (i) => ox + pad + (i / (len - 1)) * (cw - 2 * pad);
      const Y = (v) => mid - Math.max(-1, Math.min(1, v / peak)) * (ch / 2 - pad);
      g.strokeStyle = "#262626"; g.lineWidth = 1;
      g.beginPath(); g.moveTo(ox + pad, mid); g.lineTo(ox + cw - pad, mid); g.stroke();
      // The onset, and 300 ms after it.
      for (const ms of [0, 300]) {
        const i = (ms - t0) / dt;
        if (i < 0 || i > len - 1) continue;
        g.strokeStyle = ms ? "#2e3b44" : "#444"; g.beginPath(); g.moveTo(X(i), oy + pad); g.lineTo(X(i), oy + ch - pad); g.stroke();
      }
      const draw = (v, style, lw) => {
        if (!v || !v.length) return;
        g.strokeStyle = style; g.lineWidth = lw * dpr; g.beginPath();
        v.forEach((y, i) => (i ? g.lineTo(X(i), Y(y)) : g.moveTo(X(i), Y(y))));
        g.stroke();
      };
      draw(m.other_uv[c], "#9e9e9e", 1.2);
      draw(m.target_uv[c], "#4fc3f7", 2);
      g.fillStyle = ok(c) ? "#aaa" : "#ffb74d"; g.textAlign = "left";
      g.fillText(O.scope.names[c] + (ok(c) ? "" : ` (${STATE_STYLE[O.states[c]][1]})`), ox + pad + 2 * dpr, oy + pad);
    }
    g.fillStyle = "#777"; g.textAlign = "right"; g.textBaseline = "bottom";
    g.fillText(`±${peak.toFixed(1)} µV, ${t0.toFixed(0)}…${(t0 + dt * (len - 1)).toFixed(0)} ms`, w - 4 * dpr, h - 2 * dpr);
  }
  // Redrawn on the page's own frames when something changed (at most the browser's rate).
  function paint() {
    if (T.dirty) { drawTraces(); T.dirty = false; }
    if (A.dirty) { drawAverages(); A.dirty = false; }
    requestAnimationFrame(paint);
  }
  window.addEventListener("resize", () => { T.dirty = true; A.dirty = true; });
  requestAnimationFrame(paint);
  showState();
})();
