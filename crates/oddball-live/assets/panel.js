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
  };
  // What tests (and curious people) can read; the operator view shows the timing.
  const D = (window.oddballDiag = {
    connected: false, synced: false, frames: 0, flashes: 0, countdowns: 0, decisions: [],
    onTimes: [], onsetErrors: [], rtt: null, offset: null, frameMs: null, armMoves: 0,
    cancelled: 0, ended: false, targets: 0, planPoints: 0, lateFlashes: [], paused: false,
    fullscreen: false,
  });

  const conn = Oddball.connect(ODDBALL_WS.subject, {
    open() {
      D.connected = true;
      if (!S.ended) $("phase").textContent = "";
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
        const before = S.queue.length;
        S.queue = S.queue.filter((f) => f.at < m.after_ms);
        D.cancelled += before - S.queue.length;
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
        if (!S.ended) overlay(m.paused ? "Paused — rest a moment" : "");
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

  function drawArm() {
    const c = $("arm"), g = c.getContext("2d");
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    g.clearRect(0, 0, w, h);
    if (!S.config) return;
    const [x0, x1, z0, z1] = S.config.board_m;
    const [bx, bz] = S.config.base_m;
    // The elbow swings on a circle of the upper arm's length about the base: room for its top.
    const upper = Math.hypot(S.config.pose_m[0][0] - bx, S.config.pose_m[0][1] - bz);
    const xs = [x0, x1, bx, S.config.pose_m[0][0]], zs = [z0, z1, bz, bz + upper];
    const lo = [Math.min(...xs), Math.min(...zs)], hi = [Math.max(...xs), Math.max(...zs)];
    const u = Math.min(w, h) / 480;   // line widths scale with the picture
    const pad = 20 * u;
    const scale = Math.min((w - 2 * pad) / (hi[0] - lo[0]), (h - 2 * pad) / (hi[1] - lo[1]));
    const ox = (w - scale * (hi[0] - lo[0])) / 2, oy = (h - scale * (hi[1] - lo[1])) / 2;
    const P = (p) => [ox + (p[0] - lo[0]) * scale, h - oy - (p[1] - lo[1]) * scale];
    const line = (pts, style, lw) => {
      if (pts.length < 2) return;
      g.strokeStyle = style; g.lineWidth = lw * u; g.lineJoin = "round"; g.lineCap = "round"; g.beginPath();
      pts.forEach((p, i) => { const q = P(p); i ? g.lineTo(q[0], q[1]) : g.moveTo(q[0], q[1]); });
      g.stroke();
    };
    const a = P([x0, z1]), b = P([x1, z0]);
    g.fillStyle = "#f4f1e8"; g.fillRect(a[0], a[1], b[0] - a[0], b[1] - a[1]);
    line(S.config.plan_m, "rgba(79,195,247,0.8)", 6);
    for (const t of S.config.targets_m) {
      const q = P(t); g.strokeStyle = "#e57373"; g.lineWidth = 2 * u;
      g.beginPath(); g.arc(q[0], q[1], 8 * u, 0, 2 * Math.PI); g.stroke();
    }
    line(S.trail, "#222", 2.5);
    const [elbow, pen] = S.arm ? [S.arm.elbow_m, S.arm.pen_m] : S.config.pose_m;
    line([[bx, bz], elbow, pen], "#ff9800", 7);
    const q = P([bx, bz]); g.fillStyle = "#888"; g.fillRect(q[0] - 10 * u, q[1] - 6 * u, 20 * u, 12 * u);
  }

  function frame(ts) {
    D.frames++;
    if (S.lastFrame !== null) {
      const dt = ts - S.lastFrame;
      if (dt > 0 && dt < 100) S.frameMs += 0.05 * (dt - S.frameMs);
    }
    S.lastFrame = ts; D.frameMs = S.frameMs;
    if (S.offset !== null) {
      const now = serverNow(ts), half = S.frameMs / 2;
      // Off first, then on: a bulb never shows two flashes in one frame.
      S.lit = S.lit.filter((f) => {
        if (now - f.on < f.dur - half) return true;
        const b = S.bulbByCode.get(f.code);
        if (b) b.classList.remove("on");
        D.onTimes.push(now - f.on);
        conn.send({ t: "off", id: f.id, off_ms: now });
        return false;
      });
      S.queue = S.queue.filter((f) => {
        if (now < f.at - half) return true;
        const b = S.bulbByCode.get(f.code);
        if (b) b.classList.add("on");
        f.on = now; D.flashes++; D.onsetErrors.push(now - f.at);
        if (now - f.at > 3 * S.frameMs) D.lateFlashes.push({ id: f.id, code: f.code, at: f.at, on: now });
        conn.send({ t: "on", id: f.id, code: f.code, on_ms: now });
        S.lit.push(f);
        return false;
      });
      if (S.trial && !S.ended && !S.paused) {
        const left = S.trial.at_ms + S.trial.countdown_s * 1000 - now;
        $("count").textContent = left > 0 ? String(Math.ceil(left / 1000)) : "";
      }
    }
    if (S.armDirty) { drawArm(); S.armDirty = false; }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
