/* gerotor_twin report: interactive time plots from the embedded JSON, drawn with the vendored uPlot.
 * Drag: zoom to a time span; wheel: zoom in/out about the cursor; shift+drag (or middle button): pan;
 * double-click: whole run.  All time plots share the cursor (hover values in each legend) and the
 * time range.  No network: everything is in this page. */
(function () {
  "use strict";
  const spec = JSON.parse(document.getElementById("report-data").textContent);
  const plots = [];
  const full = spec.span;                  // [t_min, t_max] of the whole run [s]
  let syncing = false;
  const FONT = "12px system-ui, sans-serif";
  const LABEL_FONT = "bold 13px system-ui, sans-serif";

  // shaded spans [t0, t1, label, fill]: the plateaus in every plot, a panel's own intervals (e.g. alarms)
  function spansPlugin(spans) {
    return { hooks: { drawClear: u => {
      const ctx = u.ctx, r = devicePixelRatio || 1;
      const { left, top, width, height } = u.bbox;
      ctx.save();
      for (const [t0, t1, label, fill] of spans) {
        let x0 = u.valToPos(t0, "x", true), x1 = u.valToPos(t1, "x", true);
        if (x1 < left || x0 > left + width) continue;
        x0 = Math.max(x0, left); x1 = Math.min(x1, left + width);
        ctx.fillStyle = fill;
        ctx.fillRect(x0, top, Math.max(x1 - x0, r), height);
        if (label && x1 - x0 > 16 * r) {
          ctx.fillStyle = "#333";
          ctx.font = Math.round(12 * r) + "px system-ui, sans-serif";
          ctx.textAlign = "center"; ctx.textBaseline = "top";
          ctx.fillText(label, (x0 + x1) / 2, top + 2 * r);
        }
      }
      ctx.restore();
    } } };
  }

  function clampRange(min, max) {
    const span = Math.min(max - min, full[1] - full[0]);
    if (min < full[0]) { min = full[0]; max = min + span; }
    if (max > full[1]) { max = full[1]; min = max - span; }
    return [min, max];
  }

  function wheelPanPlugin() {
    return { hooks: { ready: u => {
      const over = u.over;
      over.addEventListener("wheel", e => {
        e.preventDefault();
        const { min, max } = u.scales.x;
        const xv = u.posToVal(e.offsetX, "x");
        const f = e.deltaY < 0 ? 0.75 : 1 / 0.75;
        const [a, b] = clampRange(xv - (xv - min) * f, xv + (max - xv) * f);
        u.setScale("x", { min: a, max: b });
      }, { passive: false });
      over.addEventListener("mousedown", e => {
        if (!(e.shiftKey || e.button === 1)) return;
        e.preventDefault(); e.stopImmediatePropagation();
        const x0 = e.clientX, { min, max } = u.scales.x;
        const perPx = (max - min) / (u.bbox.width / (devicePixelRatio || 1));
        const move = ev => {
          const [a, b] = clampRange(min - (ev.clientX - x0) * perPx, max - (ev.clientX - x0) * perPx);
          u.setScale("x", { min: a, max: b });
        };
        const up = () => { document.removeEventListener("mousemove", move); document.removeEventListener("mouseup", up); };
        document.addEventListener("mousemove", move);
        document.addEventListener("mouseup", up);
      }, true);
    } } };
  }

  function axisSize(u, values, axisIdx, cycleNum) {
    const axis = u.axes[axisIdx];
    if (cycleNum > 1) return axis._size;
    let size = axis.ticks.size + axis.gap;
    const longest = (values || []).reduce((acc, v) => (v.length > acc.length ? v : acc), "");
    if (longest !== "") { u.ctx.font = axis.font[0]; size += u.ctx.measureText(longest).width / (devicePixelRatio || 1); }
    return Math.ceil(size) + 4;
  }

  function fmt(dec) { return (u, v) => (v == null ? "–" : v.toFixed(dec)); }

  function makePlot(panel, el) {
    // NULL_EXPAND (2): a gap (null) also covers the other series' time stamps next to it
    const data = uPlot.join(panel.series.map(s => [s.x, s.y]), panel.series.map(() => [null, 2]));
    const series = [{ label: "time [s]", value: fmt(2) }];
    for (const s of panel.series) {
      series.push({ label: s.label, stroke: s.color, width: s.width, dash: s.dash.length ? s.dash : undefined,
                    value: fmt(s.dec), points: { show: false } });
    }
    const opts = {
      width: Math.max(320, el.clientWidth), height: panel.height,
      series: series,
      bands: panel.bands.map(b => ({ series: [b[0], b[1]], fill: b[2] })),
      scales: { x: { time: false } },
      axes: [
        { label: "time [s]", font: FONT, labelFont: LABEL_FONT, labelSize: 22 },
        { label: panel.ylabel, font: FONT, labelFont: LABEL_FONT, labelSize: 22, size: axisSize },
      ],
      cursor: { sync: { key: "gerotor-time" }, drag: { x: true, y: false } },
      legend: { live: true },
      plugins: [spansPlugin(spec.plateaus.map(p => [p[0], p[1], p[2], "rgba(0,0,0,0.07)"]).concat(panel.intervals)),
                wheelPanPlugin()],
      hooks: { setScale: [(u, key) => {
        if (key !== "x" || syncing) return;
        syncing = true;
        const { min, max } = u.scales.x;
        for (const o of plots) if (o !== u && o.scales.x.min !== min) o.setScale("x", { min, max });
        syncing = false;
      }] },
    };
    if (panel.zero) {
      opts.hooks.draw = [u => {
        const y = u.valToPos(0, "y", true), { left, top, width, height } = u.bbox;
        if (y < top || y > top + height) return;
        u.ctx.save(); u.ctx.strokeStyle = "#000"; u.ctx.lineWidth = devicePixelRatio || 1;
        u.ctx.beginPath(); u.ctx.moveTo(left, y); u.ctx.lineTo(left + width, y); u.ctx.stroke(); u.ctx.restore();
      }];
    }
    const u = new uPlot(opts, data, el);
    u.panelId = panel.id;
    return u;
  }

  for (const panel of spec.panels) {
    const el = document.getElementById(panel.id);
    if (!el) { console.error("report: no element for panel " + panel.id); continue; }
    try {
      plots.push(makePlot(panel, el));
    } catch (err) {
      el.textContent = "Plot could not be drawn: " + err;
      console.error("report: panel " + panel.id + ": " + err);
    }
  }
  for (const b of document.querySelectorAll("button.reset-zoom")) {
    b.addEventListener("click", () => { if (plots.length) plots[0].setScale("x", { min: full[0], max: full[1] }); });
  }
  let pending = null;
  window.addEventListener("resize", () => {
    clearTimeout(pending);
    pending = setTimeout(() => {
      for (const u of plots) u.setSize({ width: Math.max(320, u.root.parentNode.clientWidth), height: u.height });
    }, 100);
  });
  window.gerotorReport = { plots: plots, spec: spec };
})();
