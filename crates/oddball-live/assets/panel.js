// oddball subject view: draws what the session schedules and stamps every flash with the
// requestAnimationFrame time of the frame that showed it, on the server's clock. Shows nothing
// but the task; the operator view (/operator) has the figures.
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const S = {
    offset: null,          // server_ms − page_ms
    bestRtt: Infinity,
    pingId: 0,
    pings: new Map(),
    frameMs: 1000 / 60,
    lastFrame: null,
    config: null,
    bulbByCode: new Map(),
    queue: [],             // flashes waiting to go on
    lit: [],               // flashes on screen
    trial: null,
    trail: [],
    arm: null,
    armDirty: true,
    ended: null,
    paused: false,
    // Frames since the last report to the server: count, longest gap, gaps of several frame
    // periods while flashing, frames with more than one bulb lit; when the last report went.
    rep: { frames: 0, maxGap: 0, dropped: 0, multiLit: 0, at: null },
  };
  // What tests (and curious people) can read; the operator view shows the timing.
  const D = (window.oddballDiag = {
    connected: false, synced: false, frames: 0, flashes: 0, countdowns: 0, decisions: [],
    onTimes: [], onsetErrors: [], rtt: null, offset: null, frameMs: null, armMoves: 0,
    cancelled: 0, ended: false, targets: 0, planPoints: 0, lateFlashes: [], paused: false,
    fullscreen: false,
    // Flashes not drawn: too late to draw (the server voids them anyway), another one due in
    // the same frame, or the page hidden; frames with more than one bulb lit; frame gaps while
    // flashing; the view box of the drawing (metres: x0, z0, x1, z1).
    skipped: 0, skippedHidden: 0, multiLit: 0, dropped: 0, view: null,
    // Every flash drawn: its schedule (at, dur) and the server times of the frames that drew
    // it and took it off (on, off), ms.
    drawn: [],
  });

  const conn = Oddball.connect(ODDBALL_WS.subject, {
    open() {
      D.connected = true;
      if (!S.ended) $("phase").textContent = "";
      conn.send({ t: "visibility", hidden: document.hidden });
      for (let i = 0; i < 8; i++) setTimeout(ping, i * 60);
      setTimeout(() => conn.send({ t: "hello", frame_ms: S.frameMs, agent: navigator.userAgent.slice(0, 200) }), 600);
    },
    message: onMessage,
    close(ended) {
      D.connected = false;
      if (!ended) $("phase").textContent = "connection lost — retrying";
    },
  });
  function ping() {
    const id = ++S.pingId;
    const page_ms = performance.now();
    S.pings.set(id, page_ms);
    conn.send({ t: "ping", id, page_ms });
  }
  setInterval(() => { if (D.connected) ping(); }, 2000);
  function serverNow(pageMs) { return pageMs + S.offset; }

  // Full screen on a click or the F key (browsers allow it only on a gesture); the layout fills
  // the window either way.
  function fullscreen() {
    if (!document.fullscreenElement && document.documentElement.requestFullscreen) {
      document.documentElement.requestFullscreen().catch(() => {});
    }
  }
  document.addEventListener("click", fullscreen);
  document.addEventListener("keydown", (e) => { if (e.key === "f" || e.key === "F") fullscreen(); });
  document.addEventListener("fullscreenchange", () => {
    D.fullscreen = !!document.fullscreenElement;
    $("hint").style.display = D.fullscreen ? "none" : "";
    S.armDirty = true;
  });
  window.addEventListener("resize", () => { S.armDirty = true; });
  // Hidden (another tab, minimised), the browser draws nothing: the server holds a calibration
  // until the page is back. Frame gaps are judged afresh from then.
  document.addEventListener("visibilitychange", () => {
    conn.send({ t: "visibility", hidden: document.hidden });
    S.lastFrame = null;
    S.rep = { frames: 0, maxGap: 0, dropped: 0, multiLit: 0, at: null };
  });

  function overlay(text) {
    $("overlay").textContent = text || "";
    $("overlay").classList.toggle("show", !!text);
  }

  function onMessage(m) {
    switch (m.t) {
      case "config": {
        S.config = m;
        D.targets = m.targets_m.length; D.planPoints = m.plan_m.length;
        S.bulbByCode.clear();
        for (const [code, label] of m.bulbs) S.bulbByCode.set(code, $("bulb-" + label));
        S.armDirty = true;
        break;
      }
      case "pong": {
        const now = performance.now();
        const sent = S.pings.get(m.id);
        S.pings.delete(m.id);
        if (sent === undefined) break;
        const rtt = now - sent;
        if (rtt <= S.bestRtt) {
          S.bestRtt = rtt;
          S.offset = m.server_ms - (sent + rtt / 2);
          D.rtt = rtt; D.offset = S.offset; D.synced = true;
          // The operator view shows the clock figures.
          conn.send({ t: "clock", offset_ms: S.offset, rtt_ms: rtt });
        }
        break;
      }
      case "trial": {
        S.trial = m;
        D.countdowns++;
        for (const b of S.bulbByCode.values()) b.classList.remove("cue", "chosen", "wrong");
        if (m.cue !== null && S.bulbByCode.has(m.cue)) S.bulbByCode.get(m.cue).classList.add("cue");
        $("phase").textContent = m.cue !== null ? "look at the blue bulb" : "";
        break;
      }
      case "flash": S.queue.push({ id: m.id, code: m.code, at: m.at_ms, dur: m.dur_ms, on: null }); break;
      case "cancel": {
        // The trial is over: every flash still waiting is void, due or not (a page that was
        // held up must not light them during the next countdown).
        D.cancelled += S.queue.length;
        S.queue = [];
        break;
      }
      case "decision": {
        D.decisions.push(m);
        const b = m.code !== null ? S.bulbByCode.get(m.code) : null;
        const right = m.intended === null || m.intended === m.code;
        if (b) b.classList.add(right ? "chosen" : "wrong");
        const label = Oddball.label(S.config, m.code);
        $("last").textContent = m.code === null ? "no decision — the arm stays" : `${Oddball.ARROWS[label] || ""} ${label}`;
        $("last").className = m.code === null || m.intended === null ? "" : (right ? "right" : "wrong");
        break;
      }
      case "arm": {
        if (S.arm && (S.arm.pen_m[0] !== m.pen_m[0] || S.arm.pen_m[1] !== m.pen_m[1])) D.armMoves++;
        S.arm = m;
        const last = S.trail[S.trail.length - 1];
        if (!last || Math.hypot(last[0] - m.pen_m[0], last[1] - m.pen_m[1]) > 5e-4) S.trail.push(m.pen_m);
        S.armDirty = true;
        break;
      }
      case "paused": {
        S.paused = m.paused; D.paused = m.paused;
        if (!S.ended) overlay("");
        if (!S.ended && m.paused) overlay(m.fault ? "Paused — keep this window in front" : "Paused — rest a moment");
        if (m.paused) { $("count").textContent = ""; $("phase").textContent = ""; }
        break;
      }
      case "end": {
        S.ended = m.summary; D.ended = true;
        S.queue = [];
        for (const b of S.bulbByCode.values()) b.classList.remove("cue", "on");
        // Said where the countdown was, leaving the bulbs, the last decision and the arm's
        // drawing in view.
        overlay("");
        $("count").textContent = "Session over";
        $("count").classList.add("over");
        $("phase").textContent = "thank you!";
        break;
      }
    }
  }

  // The board as the person needs it: what they are drawing, large. The main view frames the
  // drawing (the planned shape or path, the targets, the pen's trace and the pen) with room
  // around it, never less than a fifth of the board; a small view beside the last decision
  // shows the whole arm on its board and where the main view is.
  function drawArm() {
    const c = $("arm"), g = c.getContext("2d");
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    g.clearRect(0, 0, w, h);
    if (!S.config) return;
    const cfg = S.config;
    const [x0, x1, z0, z1] = cfg.board_m;
    const [bx, bz] = cfg.base_m;
    const [elbow, pen] = S.arm ? [S.arm.elbow_m, S.arm.pen_m] : cfg.pose_m;
    const u = Math.min(w, h) / 480;   // line widths scale with the picture
    const pts = [...cfg.plan_m, ...cfg.targets_m, ...S.trail, pen];
    const lo = [Math.min(...pts.map((p) => p[0])), Math.min(...pts.map((p) => p[1]))];
    const hi = [Math.max(...pts.map((p) => p[0])), Math.max(...pts.map((p) => p[1]))];
    const least = 0.2 * Math.min(x1 - x0, z1 - z0);
    const span = [Math.max(1.3 * (hi[0] - lo[0]), least), Math.max(1.3 * (hi[1] - lo[1]), least)];
    const mid = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2];
    const pad = 12 * u;
    const scale = Math.min((w - 2 * pad) / span[0], (h - 2 * pad) / span[1]);
    const P = (p) => [w / 2 + (p[0] - mid[0]) * scale, h / 2 - (p[1] - mid[1]) * scale];
    D.view = [mid[0] - w / 2 / scale, mid[1] - h / 2 / scale, mid[0] + w / 2 / scale, mid[1] + h / 2 / scale];
    const line = (pts, style, lw, P_) => {
      if (pts.length < 2) return;
      g.strokeStyle = style; g.lineWidth = lw; g.lineJoin = "round"; g.lineCap = "round"; g.beginPath();
      pts.forEach((p, i) => { const q = P_(p); i ? g.lineTo(q[0], q[1]) : g.moveTo(q[0], q[1]); });
      g.stroke();
    };
    // The paper, with a faint grid of 1, 2 or 5 cm (about ten lines across).
    const a = P([x0, z1]), b = P([x1, z0]);
    g.fillStyle = "#f4f1e8"; g.fillRect(a[0], a[1], b[0] - a[0], b[1] - a[1]);
    const cell = [0.01, 0.02, 0.05, 0.1].find((s) => Math.max(...span) / s <= 12) || 0.2;
    g.save();
    g.beginPath(); g.rect(a[0], a[1], b[0] - a[0], b[1] - a[1]); g.clip();
    g.strokeStyle = "rgba(0,0,0,0.08)"; g.lineWidth = 1.5 * u;
    for (let x = Math.ceil(D.view[0] / cell) * cell; x <= D.view[2]; x += cell) line([[x, D.view[1]], [x, D.view[3]]], g.strokeStyle, 1.5 * u, P);
    for (let z = Math.ceil(D.view[1] / cell) * cell; z <= D.view[3]; z += cell) line([[D.view[0], z], [D.view[2], z]], g.strokeStyle, 1.5 * u, P);
    // The plan: a wide blue band to follow, its start marked.
    line(cfg.plan_m, "rgba(79,195,247,0.55)", 22 * u, P);
    const k = cfg.plan_m.length;
    if (k >= 2) {
      // An arrowhead at its end: the way to go.
      const [p, q] = [P(cfg.plan_m[k - 2]), P(cfg.plan_m[k - 1])];
      const ang = Math.atan2(q[1] - p[1], q[0] - p[0]), r = 30 * u;
      g.fillStyle = "rgba(41,121,255,0.85)"; g.beginPath();
      g.moveTo(q[0] + r * Math.cos(ang), q[1] + r * Math.sin(ang));
      g.lineTo(q[0] + r * Math.cos(ang + 2.4), q[1] + r * Math.sin(ang + 2.4));
      g.lineTo(q[0] + r * Math.cos(ang - 2.4), q[1] + r * Math.sin(ang - 2.4));
      g.closePath(); g.fill();
    }
    for (const t of cfg.targets_m) {
      const q = P(t); g.strokeStyle = "#e53935"; g.lineWidth = 5 * u;
      g.beginPath(); g.arc(q[0], q[1], 22 * u, 0, 2 * Math.PI); g.stroke();
      g.beginPath(); g.arc(q[0], q[1], 6 * u, 0, 2 * Math.PI); g.fillStyle = "#e53935"; g.fill();
    }
    // What the pen drew: a bold ink line, and the pen itself.
    line(S.trail, "#1a1a1a", 9 * u, P);
    const q = P(pen);
    g.fillStyle = "#ff9800"; g.strokeStyle = "#1a1a1a"; g.lineWidth = 3 * u;
    g.beginPath(); g.arc(q[0], q[1], 13 * u, 0, 2 * Math.PI); g.fill(); g.stroke();
    g.restore();
    // Beside the last decision, small: the whole arm on its board, the main view's frame on it.
    const mc = $("mini"), mg = mc.getContext("2d");
    const iw = Math.max(1, Math.round(mc.clientWidth * dpr)), ih = Math.max(1, Math.round(mc.clientHeight * dpr));
    if (mc.width !== iw || mc.height !== ih) { mc.width = iw; mc.height = ih; }
    mg.clearRect(0, 0, iw, ih);
    const upper = Math.hypot(cfg.pose_m[0][0] - bx, cfg.pose_m[0][1] - bz);
    const xs = [x0, x1, bx, cfg.pose_m[0][0]], zs = [z0, z1, bz, bz + upper];
    const ilo = [Math.min(...xs), Math.min(...zs)], ihi = [Math.max(...xs), Math.max(...zs)];
    const m = 4 * dpr, v = Math.min(iw, ih) / 120;
    const is = Math.min((iw - 2 * m) / (ihi[0] - ilo[0]), (ih - 2 * m) / (ihi[1] - ilo[1]));
    const I = (p) => [(iw - is * (ihi[0] - ilo[0])) / 2 + (p[0] - ilo[0]) * is,
                      ih - (ih - is * (ihi[1] - ilo[1])) / 2 - (p[1] - ilo[1]) * is];
    const ia = I([x0, z1]), ib = I([x1, z0]);
    mg.fillStyle = "#bdbab2"; mg.fillRect(ia[0], ia[1], ib[0] - ia[0], ib[1] - ia[1]);
    const mline = (pts, style, lw) => {
      if (pts.length < 2) return;
      mg.strokeStyle = style; mg.lineWidth = lw; mg.lineJoin = "round"; mg.lineCap = "round"; mg.beginPath();
      pts.forEach((p, i) => { const q = I(p); i ? mg.lineTo(q[0], q[1]) : mg.moveTo(q[0], q[1]); });
      mg.stroke();
    };
    mline(S.trail, "#222", 1.5 * v);
    mline([[bx, bz], elbow, pen], "#ff9800", 4 * v);
    const va = I([D.view[0], D.view[3]]), vb = I([D.view[2], D.view[1]]);
    mg.strokeStyle = "#4fc3f7"; mg.lineWidth = 1.5 * v; mg.strokeRect(va[0], va[1], vb[0] - va[0], vb[1] - va[1]);
  }

  function frame(ts) {
    D.frames++;
    const flashing = S.queue.length > 0 || S.lit.length > 0;
    if (S.lastFrame !== null) {
      const dt = ts - S.lastFrame;
      if (dt > 0 && dt < 100) S.frameMs += 0.05 * (dt - S.frameMs);
      S.rep.maxGap = Math.max(S.rep.maxGap, dt);
      // A gap of several frame periods while flashing: frames missed.
      if (flashing && !document.hidden && dt > Math.max(2.5 * S.frameMs, 40)) { S.rep.dropped++; D.dropped++; }
    }
    S.lastFrame = ts; D.frameMs = S.frameMs;
    S.rep.frames++;
    if (S.offset !== null) {
      const now = serverNow(ts), half = S.frameMs / 2;
      // Off first, then on: a bulb never shows two flashes in one frame.
      const off = (f) => {
        const b = S.bulbByCode.get(f.code);
        if (b) b.classList.remove("on");
        D.onTimes.push(now - f.on);
        D.drawn.push({ at: f.at, dur: f.dur, on: f.on, off: now });
        conn.send({ t: "off", id: f.id, off_ms: now });
      };
      S.lit = S.lit.filter((f) => {
        if (now - f.on < f.dur - half) return true;
        off(f);
        return false;
      });
      // The flashes due now: at most one goes on (the latest); any other is skipped, as is
      // one too late to draw (the server voids it: no burst of stale flashes after a stall)
      // and any while the page is hidden (nobody sees it).
      const due = S.queue.filter((f) => now >= f.at - half);
      S.queue = S.queue.filter((f) => now < f.at - half);
      const limit = S.config ? S.config.undrawn_after_ms : 200;
      const f = due.pop();
      D.skipped += due.length;
      if (f && (document.hidden || now - f.at > limit)) {
        D.skipped++;
        if (document.hidden) D.skippedHidden++;
      } else if (f) {
        // One bulb at a time: one still lit (no gap in the schedule, a frame late) goes off.
        S.lit.forEach(off);
        S.lit = [];
        const b = S.bulbByCode.get(f.code);
        if (b) b.classList.add("on");
        f.on = now; D.flashes++; D.onsetErrors.push(now - f.at);
        if (now - f.at > 3 * S.frameMs) D.lateFlashes.push({ id: f.id, code: f.code, at: f.at, on: now });
        conn.send({ t: "on", id: f.id, code: f.code, on_ms: now });
        S.lit.push(f);
      }
      if (S.trial && !S.ended && !S.paused) {
        const left = S.trial.at_ms + S.trial.countdown_s * 1000 - now;
        $("count").textContent = left > 0 ? String(Math.ceil(left / 1000)) : "";
      }
    }
    // The page checks itself: more than one bulb lit in this frame is a fault.
    if (document.querySelectorAll(".bulb.on").length > 1) { S.rep.multiLit++; D.multiLit++; }
    if (S.rep.at === null) S.rep.at = ts;
    const every = S.config ? S.config.frames_every_ms : 250;
    if (ts - S.rep.at >= every) {
      conn.send({ t: "frames", frames: S.rep.frames, max_gap_ms: Math.min(S.rep.maxGap, 1e7),
                  dropped: S.rep.dropped, multi_lit: S.rep.multiLit });
      S.rep = { frames: 0, maxGap: 0, dropped: 0, multiLit: 0, at: ts };
    }
    if (S.armDirty) { drawArm(); S.armDirty = false; }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
