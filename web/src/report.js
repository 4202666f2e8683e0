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
import { drawPoint } from "chart.js/helpers";

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

// Legend samples drawn by us, all as wide as a dash needs: Chart.js's own point styles in
// a legend are as wide as its font is high, or stretched (circles into ellipses).
const SAMPLE_W = 30;
const SAMPLE_H = 14;
function sample(e) {
  const c = document.createElement("canvas");
  c.width = SAMPLE_W;
  c.height = SAMPLE_H;
  const g = c.getContext("2d");
  const s = e.swatch;
  g.strokeStyle = e.color;
  if (s.kind === "line") {
    g.lineWidth = 2.5;
    g.setLineDash(dash(s.dash));
    g.beginPath();
    g.moveTo(1, SAMPLE_H / 2);
    g.lineTo(SAMPLE_W - 1, SAMPLE_H / 2);
    g.stroke();
  } else if (s.kind === "marker") {
    g.fillStyle = s.filled ? withAlpha(e.color, 0.8) : "rgba(0, 0, 0, 0)";
    drawPoint(g, { pointStyle: marker(s.marker), radius: 5, borderWidth: 1.5, rotation: 0 }, SAMPLE_W / 2, SAMPLE_H / 2);
  } else {
    g.fillStyle = withAlpha(e.color, s.alpha);
    g.lineWidth = 1;
    g.fillRect(4, 2, SAMPLE_W - 8, SAMPLE_H - 4);
    g.strokeRect(4.5, 2.5, SAMPLE_W - 9, SAMPLE_H - 5);
  }
  return c;
}

// The figure's own legend (colour → policy, marker → setting, dash → sweep axis value),
// not one entry per dataset. `marker` and `lineDash` say what each sample shows.
function legendItems(figure) {
  return figure.legend.map((e) => ({
    text: e.text,
    fontColor: INK,
    hidden: false,
    pointStyle: sample(e),
    strokeStyle: e.color,
    fillStyle: e.color,
    lineWidth: 0,
    lineDash: e.swatch.kind === "line" ? dash(e.swatch.dash) : [],
    marker: e.swatch.kind === "marker" ? marker(e.swatch.marker) : undefined,
  }));
}

function legend(figure) {
  return {
    position: "bottom",
    onClick: () => {},
    labels: {
      usePointStyle: true,
      pointStyleWidth: SAMPLE_W,
      boxHeight: SAMPLE_H,
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
        point_style: i.marker ?? (typeof i.pointStyle === "string" ? i.pointStyle : "sample"),
        line_dash: i.lineDash ?? [],
      })),
    },
  ]),
);
