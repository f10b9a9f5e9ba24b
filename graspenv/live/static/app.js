// graspenv live table: sends touches over the WebSocket, draws the server's views.
"use strict";
(() => {
  const canvas = document.getElementById("table");
  const ctx = canvas.getContext("2d");
  const $ = (id) => document.getElementById(id);
  let table = [0.61, 0.46];      // metres, from the server's views
  let resolution = [640, 480];   // mask pixels
  let socket = null;
  let view = null;
  const maskImage = new Image();
  const DEFAULT_GAP = 0.08;      // metres between a mouse pinch's fingertips
  const mouse = { down: false, pinch: false, x: 0, y: 0, gap: DEFAULT_GAP, angle: 0 };
  const touches = new Map();     // browser touch id -> touch

  // -- layout: the whole table fills the canvas, at its aspect ratio ------------------
  function fit() {
    const main = canvas.parentElement.getBoundingClientRect();
    const aspect = table[0] / table[1];
    let w = main.width, h = main.width / aspect;
    if (h > main.height) { h = main.height; w = h * aspect; }
    canvas.style.width = `${Math.floor(w)}px`;
    canvas.style.height = `${Math.floor(h)}px`;
    const dpr = window.devicePixelRatio || 1;
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
    draw();
  }
  window.addEventListener("resize", fit);

  // -- input: every change sends the whole set of this page's touches ----------------
  function normalised(clientX, clientY) {
    const r = canvas.getBoundingClientRect();
    const clamp = (v) => Math.min(1, Math.max(0, v));
    return { x: clamp((clientX - r.left) / r.width), y: clamp((clientY - r.top) / r.height),
             w: r.width, h: r.height };
  }
  function fromTouch(t) {
    const p = normalised(t.clientX, t.clientY);
    const rx = t.radiusX > 0 ? t.radiusX / p.w : null;
    const ry = t.radiusY > 0 ? t.radiusY / p.h : null;
    return { x: p.x, y: p.y, rx, ry, angle: ((t.rotationAngle || 0) * Math.PI) / 180 };
  }
  function mouseTouches() {
    if (!mouse.down) return [];
    if (!mouse.pinch) return [{ x: mouse.x, y: mouse.y, rx: null, ry: null, angle: 0 }];
    const dx = (0.5 * mouse.gap * Math.cos(mouse.angle)) / table[0];
    const dy = (0.5 * mouse.gap * Math.sin(mouse.angle)) / table[1];
    const clamp = (v) => Math.min(1, Math.max(0, v));
    return [
      { x: clamp(mouse.x - dx), y: clamp(mouse.y + dy), rx: null, ry: null, angle: 0 },
      { x: clamp(mouse.x + dx), y: clamp(mouse.y - dy), rx: null, ry: null, angle: 0 },
    ];
  }
  function send() {
    if (!socket || socket.readyState !== WebSocket.OPEN) return;
    const all = [...touches.values(), ...mouseTouches()].slice(0, 64);
    socket.send(JSON.stringify({ type: "touches", touches: all }));
  }
  function onTouch(e) {
    e.preventDefault();
    for (const t of e.changedTouches) {
      if (e.type === "touchend" || e.type === "touchcancel") touches.delete(t.identifier);
      else touches.set(t.identifier, fromTouch(t));
    }
    send();
  }
  for (const type of ["touchstart", "touchmove", "touchend", "touchcancel"]) {
    canvas.addEventListener(type, onTouch, { passive: false });
  }
  canvas.addEventListener("pointerdown", (e) => {
    if (e.pointerType !== "mouse") return;
    e.preventDefault();
    canvas.setPointerCapture(e.pointerId);
    Object.assign(mouse, normalised(e.clientX, e.clientY));
    mouse.down = true;
    mouse.pinch = e.shiftKey || e.button === 2;
    send();
  });
  canvas.addEventListener("pointermove", (e) => {
    if (e.pointerType !== "mouse" || !mouse.down) return;
    Object.assign(mouse, normalised(e.clientX, e.clientY));
    send();
  });
  const up = (e) => {
    if (e.pointerType !== "mouse" || !mouse.down) return;
    mouse.down = false;
    send();
  };
  canvas.addEventListener("pointerup", up);
  canvas.addEventListener("pointercancel", up);
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    // Some browsers turn Shift+wheel into a horizontal scroll.
    const step = Math.sign(e.deltaY || e.deltaX);
    if (e.shiftKey) mouse.angle += step * (Math.PI / 36);           // 5° a notch
    else mouse.gap = Math.min(0.3, Math.max(0.01, mouse.gap + step * 0.001)); // 1 mm
    if (mouse.down && mouse.pinch) send();
  }, { passive: false });
  $("reset").addEventListener("click", () => {
    if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({ type: "reset" }));
    else fetch("/reset", { method: "POST" });
  });

  // -- drawing -----------------------------------------------------------------------
  function path(points, close) {
    const sx = canvas.width / resolution[0], sy = canvas.height / resolution[1];
    ctx.beginPath();
    points.forEach(([x, y], i) => {
      const X = (x + 0.5) * sx, Y = (y + 0.5) * sy;
      if (i === 0) ctx.moveTo(X, Y); else ctx.lineTo(X, Y);
    });
    if (close) ctx.closePath();
  }
  function colour(i) { return `hsl(${(i * 137.5) % 360} 80% 60%)`; }
  function draw() {
    ctx.fillStyle = "#000";
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    if (!view) return;
    ctx.imageSmoothingEnabled = false;
    if (maskImage.complete && maskImage.naturalWidth) {
      ctx.globalAlpha = 0.45;
      ctx.drawImage(maskImage, 0, 0, canvas.width, canvas.height);
      ctx.globalAlpha = 1;
    }
    const lw = Math.max(1, canvas.width / 500);
    if (view.goal) {
      ctx.setLineDash([6 * lw, 4 * lw]);
      ctx.strokeStyle = "#66bb6a"; ctx.lineWidth = 2 * lw;
      path(view.goal.outline, true); ctx.stroke();
      ctx.setLineDash([]);
    }
    for (const obj of Object.values(view.outlines)) {
      // Lighter the higher the object stands above the table (0 to 10 cm).
      const lift = Math.min(1, Math.max(0, obj.height / 0.1));
      ctx.fillStyle = `hsla(210, 80%, ${35 + 40 * lift}%, 0.55)`;
      ctx.strokeStyle = "#90caf9"; ctx.lineWidth = 2 * lw;
      path(obj.outline, true); ctx.fill(); ctx.stroke();
    }
    view.contours.forEach((c, i) => {
      ctx.strokeStyle = colour(i); ctx.lineWidth = 1.5 * lw;
      path(c, true); ctx.stroke();
    });
    ctx.fillStyle = "#ff5252";
    const sx = canvas.width / resolution[0], sy = canvas.height / resolution[1];
    for (const [x, y] of view.particles) {
      ctx.beginPath(); ctx.arc((x + 0.5) * sx, (y + 0.5) * sy, 1.6 * lw, 0, 2 * Math.PI); ctx.fill();
    }
  }
  function show(v) {
    const first = !view;
    view = v;
    if (first || v.table[0] !== table[0] || v.table[1] !== table[1]) {
      table = v.table; resolution = v.resolution; fit();
    }
    $("frame").textContent = v.frame;
    $("fps").textContent = v.fps.toFixed(1);
    $("dropped").textContent = `${v.dropped} dropped`;
    $("dropped").className = v.dropped > 0 ? "figure late" : "figure";
    $("contacts").textContent = v.contacts;
    const grip = Object.values(v.grip_force).reduce((a, b) => a + b, 0);
    $("grip").textContent = grip.toFixed(2);
    const heights = Object.values(v.objects).map((o) => (o.position[2] * 1000).toFixed(1));
    $("height").textContent = heights.join(", ");
    $("task").textContent = v.task ? `task: ${v.task}` : "";
    const s = $("success");
    if (v.success === null) { s.textContent = ""; s.className = ""; }
    else { s.textContent = v.success ? "success" : "not yet"; s.className = v.success ? "yes" : "no"; }
    if (v.mask) maskImage.src = `data:image/png;base64,${v.mask}`;
    draw();
  }
  maskImage.onload = draw;

  // -- the socket, reconnecting ------------------------------------------------------
  function connect() {
    const scheme = location.protocol === "https:" ? "wss" : "ws";
    socket = new WebSocket(`${scheme}://${location.host}/ws`);
    socket.onopen = () => { $("status").textContent = "connected"; send(); };
    socket.onmessage = (e) => {
      const m = JSON.parse(e.data);
      if (m.type === "view") show(m);
      else if (m.type === "error") $("status").textContent = `server: ${m.message}`;
    };
    socket.onclose = () => {
      $("status").textContent = "disconnected, retrying…";
      setTimeout(connect, 1000);
    };
  }
  fit();
  connect();
})();
