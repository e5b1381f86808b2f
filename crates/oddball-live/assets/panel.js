// oddball stimulus panel: draws what the session schedules and stamps every flash with the
// requestAnimationFrame time of the frame that showed it, on the server's clock.
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const S = {
    ws: null,
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
  };
  // What tests (and curious people) can read.
  const D = (window.oddballDiag = {
    connected: false, synced: false, frames: 0, flashes: 0, countdowns: 0, decisions: [],
    onTimes: [], onsetErrors: [], rtt: null, offset: null, frameMs: null, armMoves: 0,
    cancelled: 0, ended: false, serverDiag: "", targets: 0, planPoints: 0, lateFlashes: [],
  });

  function send(obj) {
    if (S.ws && S.ws.readyState === 1) S.ws.send(JSON.stringify(obj));
  }
  function ping() {
    const id = ++S.pingId;
    const page_ms = performance.now();
    S.pings.set(id, page_ms);
    send({ t: "ping", id, page_ms });
  }
  function serverNow(pageMs) { return pageMs + S.offset; }

  function connect() {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    S.ws = ws;
    ws.onopen = () => {
      D.connected = true;
      $("status").textContent = "connected";
      for (let i = 0; i < 8; i++) setTimeout(ping, i * 60);
      setTimeout(() => send({ t: "hello", frame_ms: S.frameMs, agent: navigator.userAgent.slice(0, 200) }), 600);
    };
    ws.onclose = () => {
      D.connected = false;
      $("status").textContent = S.ended ? "session over" : "disconnected — retrying";
      if (!S.ended) setTimeout(connect, 1000);
    };
    ws.onmessage = (ev) => onMessage(JSON.parse(ev.data));
  }
  setInterval(() => { if (D.connected) ping(); }, 2000);

  function onMessage(m) {
    switch (m.t) {
      case "config": {
        S.config = m;
        D.targets = m.targets_m.length; D.planPoints = m.plan_m.length;
        $("title").textContent = m.title;
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
        }
        break;
      }
      case "trial": {
        S.trial = m;
        D.countdowns++;
        for (const b of S.bulbByCode.values()) b.classList.remove("cue", "chosen", "wrong");
        if (m.cue !== null && S.bulbByCode.has(m.cue)) S.bulbByCode.get(m.cue).classList.add("cue");
        $("phase").textContent = m.phase === "calibration" ? "calibration: look at the blue bulb"
          : (m.cue !== null ? "look at the blue bulb" : "");
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
        if (b) b.classList.add(m.intended === null || m.intended === m.code ? "chosen" : "wrong");
        const label = m.code === null ? "abstained" : (S.config ? S.config.bulbs.find((x) => x[0] === m.code)[1] : m.code);
        const line = document.createElement("div");
        const p = m.posterior.length ? Math.max(...m.posterior).toFixed(2) : "";
        line.textContent = `#${m.trial} ${label}` + (m.intended !== null && m.code !== null ? (m.intended === m.code ? " ✓" : " ✗") : "")
          + ` p=${p} rounds=${m.rounds}` + (m.refused ? ` (arm refused: ${m.refused})` : "");
        $("decisions").prepend(line);
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
      case "diag": D.serverDiag = m.text; break;
      case "end": {
        S.ended = m.summary; D.ended = true;
        $("status").textContent = "session over";
        $("count").textContent = "";
        $("phase").textContent = m.summary;
        break;
      }
    }
  }

  function stats(xs) {
    if (!xs.length) return "–";
    const n = xs.length, mean = xs.reduce((a, b) => a + b, 0) / n;
    const sd = Math.sqrt(xs.reduce((a, b) => a + (b - mean) ** 2, 0) / n);
    return `${mean.toFixed(1)} ± ${sd.toFixed(1)} [${Math.min(...xs).toFixed(1)}, ${Math.max(...xs).toFixed(1)}] n=${n}`;
  }
  let diagAt = 0;
  function showDiag(ts) {
    if (ts - diagAt < 500) return;
    diagAt = ts;
    $("diag").textContent =
      `clock offset  ${S.offset === null ? "–" : S.offset.toFixed(1)} ms (rtt ${D.rtt === null ? "–" : D.rtt.toFixed(2)} ms)\n` +
      `frame         ${S.frameMs.toFixed(2)} ms\n` +
      `flashes drawn ${D.flashes}   cancelled ${D.cancelled}\n` +
      `on-time ms    ${stats(D.onTimes.slice(-200))}\n` +
      `onset − plan  ${stats(D.onsetErrors.slice(-200))}\n` + D.serverDiag;
  }

  function drawArm() {
    const c = $("arm"), g = c.getContext("2d");
    g.clearRect(0, 0, c.width, c.height);
    if (!S.config) return;
    const [x0, x1, z0, z1] = S.config.board_m;
    const [bx, bz] = S.config.base_m;
    const xs = [x0, x1, bx], zs = [z0, z1, bz];
    const lo = [Math.min(...xs), Math.min(...zs)], hi = [Math.max(...xs), Math.max(...zs)];
    const pad = 20, scale = Math.min((c.width - 2 * pad) / (hi[0] - lo[0]), (c.height - 2 * pad) / (hi[1] - lo[1]));
    const P = (p) => [pad + (p[0] - lo[0]) * scale, c.height - pad - (p[1] - lo[1]) * scale];
    const line = (pts, style, w) => {
      if (pts.length < 2) return;
      g.strokeStyle = style; g.lineWidth = w; g.beginPath();
      pts.forEach((p, i) => { const q = P(p); i ? g.lineTo(q[0], q[1]) : g.moveTo(q[0], q[1]); });
      g.stroke();
    };
    const a = P([x0, z1]), b = P([x1, z0]);
    g.fillStyle = "#f4f1e8"; g.fillRect(a[0], a[1], b[0] - a[0], b[1] - a[1]);
    line(S.config.plan_m, "rgba(79,195,247,0.8)", 6);
    for (const t of S.config.targets_m) {
      const q = P(t); g.strokeStyle = "#e57373"; g.lineWidth = 2;
      g.beginPath(); g.arc(q[0], q[1], 8, 0, 2 * Math.PI); g.stroke();
    }
    line(S.trail, "#222", 2.5);
    if (S.arm) line([[bx, bz], S.arm.elbow_m, S.arm.pen_m], "#ff9800", 7);
    const q = P([bx, bz]); g.fillStyle = "#888"; g.fillRect(q[0] - 10, q[1] - 6, 20, 12);
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
        send({ t: "off", id: f.id, off_ms: now });
        return false;
      });
      S.queue = S.queue.filter((f) => {
        if (now < f.at - half) return true;
        const b = S.bulbByCode.get(f.code);
        if (b) b.classList.add("on");
        f.on = now; D.flashes++; D.onsetErrors.push(now - f.at);
        if (now - f.at > 3 * S.frameMs) D.lateFlashes.push({ id: f.id, code: f.code, at: f.at, on: now });
        send({ t: "on", id: f.id, code: f.code, on_ms: now });
        S.lit.push(f);
        return false;
      });
      if (S.trial && !S.ended) {
        const left = S.trial.at_ms + S.trial.countdown_s * 1000 - now;
        $("count").textContent = left > 0 ? String(Math.ceil(left / 1000)) : "";
      }
    }
    if (S.armDirty) { drawArm(); S.armDirty = false; }
    showDiag(ts);
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
  connect();
})();
