// The plots of `thorarena report`. The Rust side writes the tables, the warnings and one
// <canvas> per plot, and puts each figure in <script id="report-data"> as data — values,
// colour (one per policy), dash, marker and legend, the same data its SVG files are drawn
// from (src/report/figures.rs); this script only draws them with Chart.js. Animations are off: a report is a document, and a plot must
// be complete the moment the page has loaded (the browser tests check exactly that).

import {
  Chart,
  RadarController,
  ScatterController,
  BarController,
  RadialLinearScale,
  LinearScale,
  LogarithmicScale,
  CategoryScale,
  PointElement,
  LineElement,
  BarElement,
  Filler,
  Legend,
  Tooltip,
} from "chart.js";

Chart.register(
  RadarController,
  ScatterController,
  BarController,
  RadialLinearScale,
  LinearScale,
  LogarithmicScale,
  CategoryScale,
  PointElement,
  LineElement,
  BarElement,
  Filler,
  Legend,
  Tooltip,
);
Chart.defaults.animation = false;
Chart.defaults.maintainAspectRatio = false;
Chart.defaults.font.family = 'system-ui, -apple-system, "Segoe UI", sans-serif';
Chart.defaults.font.size = 13;
Chart.defaults.color = "#1d2330";

const data = JSON.parse(document.getElementById("report-data").textContent);
const INK = "#1d2330";
const dash = (i) => data.style.dashes[i % data.style.dashes.length];
const marker = (i) => data.style.markers[i % data.style.markers.length];

function withAlpha(hex, alpha) {
  const n = parseInt(hex.slice(1), 16);
  return `rgba(${(n >> 16) & 255}, ${(n >> 8) & 255}, ${n & 255}, ${alpha})`;
}

// A line legend sample wide enough to show its dash (Chart.js's own "line" point style is
// as short as a marker is wide).
function lineSample(color, lineDash) {
  const c = document.createElement("canvas");
  c.width = 30;
  c.height = 12;
  const g = c.getContext("2d");
  g.strokeStyle = color;
  g.lineWidth = 2.5;
  g.setLineDash(lineDash);
  g.beginPath();
  g.moveTo(1, 6);
  g.lineTo(29, 6);
  g.stroke();
  return c;
}

// The figure's own legend (colour → policy, marker → setting, dash → sweep axis value),
// not one entry per dataset.
function legendItems(figure) {
  return figure.legend.map((e) => {
    const s = e.swatch;
    const item = { text: e.text, fontColor: INK, hidden: false, lineWidth: 2, strokeStyle: e.color };
    if (s.kind === "line") {
      return { ...item, pointStyle: lineSample(e.color, dash(s.dash)), lineDash: dash(s.dash), fillStyle: e.color };
    }
    if (s.kind === "marker") {
      return { ...item, pointStyle: marker(s.marker), lineWidth: 1.5, fillStyle: s.filled ? e.color : "rgba(0, 0, 0, 0)" };
    }
    return { ...item, pointStyle: "rect", lineWidth: 1, fillStyle: withAlpha(e.color, s.alpha) };
  });
}

function legend(figure) {
  return {
    position: "bottom",
    onClick: () => {},
    labels: {
      usePointStyle: true,
      padding: 14,
      font: { size: 13 },
      generateLabels: () => legendItems(figure),
    },
  };
}

const tooltip = {
  callbacks: {
    label: (ctx) => {
      const e = ctx.raw?.episode;
      if (!e) return `${ctx.dataset.label}: ${ctx.formattedValue}`;
      const end = e.termination ? `, ended: ${e.termination}` : "";
      return `${data.runs[e.run].label} ${e.setting} ${e.task}/${e.sequence_id}: tracking ${e.tracking.toFixed(1)}, survival ${e.survival.toFixed(2)}, score ${e.score.toFixed(1)}${end}`;
    },
  },
};

// Ticks at round steps (0.2 over a unit range) inside [lo, hi].
function roundTicks([lo, hi]) {
  const step = hi - lo > 2 ? 10 ** Math.floor(Math.log10(hi - lo)) : 0.2;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9; v += step) out.push({ value: Math.round(v / step) * step });
  return out;
}

const axisTitle = (text) => ({ display: text !== "", text, font: { size: 13 } });

function config(f) {
  const common = (d) => ({
    label: d.label,
    policy: d.policy,
    borderColor: d.color,
    borderDash: dash(d.dash),
    pointStyle: marker(d.marker),
  });
  const plugins = { legend: legend(f), tooltip };
  if (f.kind === "radar") {
    return {
      type: "radar",
      data: {
        labels: f.categories,
        datasets: f.datasets.map((d) => ({
          ...common(d),
          data: d.values,
          backgroundColor: withAlpha(d.color, d.fill_alpha),
          pointBackgroundColor: d.color,
          borderWidth: 2,
          fill: true,
          spanGaps: false,
        })),
      },
      options: {
        scales: {
          r: {
            min: f.y_range?.[0] ?? 0,
            max: f.y_range?.[1] ?? 100,
            // Tick labels above the data, on a white backdrop: the polygons never cross them.
            ticks: { stepSize: 20, z: 2, color: INK, font: { size: 12 }, showLabelBackdrop: true, backdropColor: "rgba(255, 255, 255, 0.9)", backdropPadding: 2 },
            pointLabels: { color: INK, font: { size: 14 } },
          },
        },
        plugins,
      },
    };
  }
  if (f.kind === "scatter" || f.kind === "lines") {
    const range = (r) => (r ? { min: r[0], max: r[1] } : {});
    return {
      type: "scatter",
      data: {
        datasets: f.datasets.map((d) => ({
          ...common(d),
          data: d.points.map(([x, y], i) => ({ x, y, episode: f.kind === "scatter" ? data.episodes[d.episodes[i]] : undefined })),
          showLine: f.kind === "lines",
          backgroundColor: withAlpha(d.color, d.fill_alpha),
          borderWidth: f.kind === "lines" ? 2 : 1.2,
          pointRadius: f.kind === "scatter" ? 6 : 4,
          pointHoverRadius: 8,
        })),
      },
      options: {
        scales: {
          x: {
            type: "linear",
            title: axisTitle(f.x_label),
            ...range(f.x_range),
            // A padded range (the scatter's jitter) keeps round ticks inside it.
            afterBuildTicks: f.x_range ? (axis) => (axis.ticks = roundTicks(f.x_range)) : undefined,
          },
          y: { type: "linear", title: axisTitle(f.y_label), ...range(f.y_range) },
        },
        plugins,
      },
    };
  }
  return {
    type: "bar",
    data: {
      labels: f.categories,
      datasets: f.datasets.map((d) => ({
        ...common(d),
        data: d.values,
        backgroundColor: withAlpha(d.color, d.fill_alpha),
        borderWidth: 1,
      })),
    },
    options: {
      scales: {
        x: { ticks: { font: { size: 13 } } },
        y:
          f.kind === "log_bars"
            ? { type: "logarithmic", title: axisTitle(f.y_label) }
            : { beginAtZero: true, ticks: { precision: 0 }, title: axisTitle(f.y_label) },
      },
      plugins,
    },
  };
}

const charts = {};
for (const figure of data.figures) {
  const canvas = document.getElementById(figure.id);
  if (!canvas) throw new Error(`report: no canvas #${figure.id}`);
  charts[figure.id] = new Chart(canvas, config(figure));
}

// For tests and for a curious reader's console: which plots exist and what they hold.
window.thorarenaReport = {
  ready: true,
  plots: data.plots,
  points: Object.fromEntries(
    Object.entries(charts).map(([id, c]) => [
      id,
      c.data.datasets.reduce((n, d) => n + d.data.filter((v) => v !== null && v !== undefined).length, 0),
    ]),
  ),
};
// The charts themselves, as drawn: each dataset's policy and colours, each legend entry.
window.thorarenaCharts = Object.fromEntries(
  Object.entries(charts).map(([id, c]) => [
    id,
    {
      datasets: c.data.datasets.map((d) => ({
        label: d.label,
        policy: d.policy,
        border_color: d.borderColor,
        background_color: d.backgroundColor,
        border_dash: d.borderDash ?? [],
        point_style: d.pointStyle,
      })),
      legend: (c.legend?.legendItems ?? []).map((i) => ({
        text: i.text,
        fill_style: i.fillStyle,
        stroke_style: i.strokeStyle,
        point_style: i.pointStyle,
        line_dash: i.lineDash ?? [],
      })),
    },
  ]),
);
