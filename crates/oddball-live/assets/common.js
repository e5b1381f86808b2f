// What the subject view and the operator view share: their WebSocket connection (the paths,
// ODDBALL_WS above, come from the server's protocol module) and the bulbs' names.
"use strict";
const Oddball = {
  ARROWS: { up: "▲", down: "▼", left: "◀", right: "▶" },
  /** The name of bulb `code` ("up"), or "no decision" for null. */
  label(config, code) {
    if (code === null) return "no decision";
    const b = config && config.bulbs.find((x) => x[0] === code);
    return b ? b[1] : String(code);
  },
  /**
   * Opens `path` and keeps it open (reconnecting every second) until the session is over.
   * Handlers: open(), message(m), close(ended). Returns { send(obj) }.
   */
  connect(path, h) {
    let ws = null, ended = false;
    // The view's key, from the address the session printed: without it the server refuses.
    const key = encodeURIComponent(new URLSearchParams(location.search).get("key") || "");
    const open = () => {
      ws = new WebSocket(`ws://${location.host}${path}?key=${key}`);
      ws.onopen = () => h.open && h.open();
      ws.onmessage = (ev) => {
        const m = JSON.parse(ev.data);
        if (m.t === "end") ended = true;
        h.message(m);
      };
      ws.onclose = () => {
        if (h.close) h.close(ended);
        if (!ended) setTimeout(open, 1000);
      };
    };
    open();
    return {
      send(obj) { if (ws && ws.readyState === 1) ws.send(JSON.stringify(obj)); },
      get open() { return !!ws && ws.readyState === 1; },
    };
  },
};
