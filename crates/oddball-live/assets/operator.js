// oddball operator view: progress, signal quality, decisions, flash timing; pause, resume and
// abort. It never draws or stamps flashes (the subject view at / does).
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const S = { config: null, trial: null, paused: false, pauseAsked: false, ended: null };
  // What tests can read.
  const O = (window.oddballOperator = {
    connected: false, phase: null, number: 0, of: null, paused: false, ended: false,
    decisions: 0, channels: [], controls: [], subjectPages: 0,
  });

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
      if (S.paused) { state = `paused after ${state}`; line = "nothing flashes until Resume"; }
      else if (S.pauseAsked) line = "pausing after the decision under way…";
      else line = t.phase === "calibration" ? "cued decisions: the model learns from them" : "decisions drive the arm";
    }
    $("state").textContent = state;
    $("state").className = S.ended !== null ? "over" : (S.paused ? "paused" : "");
    $("progress-line").textContent = line;
    $("progress").value = frac;
    const over = S.ended !== null;
    $("pause").disabled = over || S.paused || S.pauseAsked;
    $("resume").disabled = over || !(S.paused || S.pauseAsked);
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
        if (S.paused) { S.paused = false; O.paused = false; }
        showState();
        break;
      case "paused":
        S.paused = m.paused; O.paused = m.paused;
        if (!m.paused) S.pauseAsked = false;
        showState();
        break;
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
  showState();
})();
