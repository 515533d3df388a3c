// The WebSocket to /api/ws: reconnects with exponential backoff, hands messages on.

export function createSocket({ onMessage, onStatus }) {
  let ws = null;
  let attempt = 0;
  let timer = null;
  let wanted = false;

  function url() {
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    return `${scheme}//${location.host}/api/ws`;
  }

  function connect() {
    clearTimeout(timer);
    timer = null;
    if (!wanted) return;
    onStatus({ status: "connecting" });
    let socket;
    try {
      socket = new WebSocket(url());
    } catch {
      retryLater(); // e.g. blocked by the browser: try again, REST keeps the page going
      return;
    }
    ws = socket;
    socket.addEventListener("open", () => {
      if (ws !== socket) return;
      attempt = 0;
      onStatus({ status: "open" });
    });
    socket.addEventListener("message", (event) => {
      let msg;
      try {
        msg = JSON.parse(event.data);
      } catch {
        return;
      }
      if (msg && typeof msg.type === "string") onMessage(msg);
    });
    socket.addEventListener("close", (event) => {
      if (ws !== socket) return;
      ws = null;
      if (event.code === 4401) {
        // not logged in (any more): no point retrying
        wanted = false;
        onStatus({ status: "closed", code: 4401 });
        return;
      }
      if (!wanted) {
        onStatus({ status: "closed" });
        return;
      }
      retryLater();
    });
  }

  function retryLater() {
    const delay = Math.min(10000, 500 * 2 ** attempt);
    attempt += 1;
    onStatus({ status: "closed" });
    timer = setTimeout(connect, delay);
  }

  return {
    start() {
      wanted = true;
      if (!ws) connect();
    },
    stop() {
      wanted = false;
      clearTimeout(timer);
      if (ws) ws.close();
      ws = null;
    },
    reconnectNow() {
      attempt = 0;
      if (!ws) connect();
    },
    isOpen: () => Boolean(ws) && ws.readyState === WebSocket.OPEN,
    /** Send a message; false when the socket is not open (the caller falls back to REST). */
    send(msg) {
      if (!ws || ws.readyState !== WebSocket.OPEN) return false;
      try {
        ws.send(JSON.stringify(msg));
        return true;
      } catch {
        return false;
      }
    },
  };
}
