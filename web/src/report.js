// The plots of `thorarena report`. The Rust side writes the tables, the warnings and one
// <canvas> per plot, and puts the numbers in <script id="report-data">; this script only
// draws them with Chart.js. Animations are off: a report is a document, and a plot must
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
import { runColor, withAlpha } from "./palette.js";

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

const data = JSON.parse(document.getElementById("report-data").textContent);
const label = (run) => data.runs[run].label;
// Settings get marker shapes, runs get colours, so both read in one scatter plot.
const MARKERS = ["circle", "triangle", "rect", "rectRot", "star", "crossRot"];
const settingsSeen = [...new Set(data.episodes.map((e) => e.setting))];
const marker = (setting) => MARKERS[settingsSeen.indexOf(setting) % MARKERS.length];

const charts = {};
function draw(id, config) {
  const canvas = document.getElementById(id);
  if (!canvas) throw new Error(`report: no canvas #${id}`);
  charts[id] = new Chart(canvas, config);
}

// A sweep's curves: a metric against the swept quantity, one line per series (runColor
// indexes series here, not runs).
for (const chart of data.sweep) {
  draw(chart.id, {
    type: "scatter",
    data: {
      datasets: chart.series.map((s, i) => ({
        label: s.label,
        data: s.points.map(([x, y]) => ({ x, y })),
        showLine: true,
        borderColor: runColor(i),
        backgroundColor: runColor(i),
        pointRadius: 4,
      })),
    },
    options: {
      scales: {
        x: { type: "linear", title: { display: true, text: chart.x_label } },
        y: { type: "linear", title: { display: true, text: chart.y_label } },
      },
      plugins: { legend: { position: "bottom" } },
    },
  });
}

for (const radar of data.radars) {
  draw(radar.id, {
    type: "radar",
    data: {
      labels: data.tasks,
      datasets: radar.series.map((s) => ({
        label: label(s.run),
        data: s.values,
        borderColor: runColor(s.run),
        backgroundColor: withAlpha(runColor(s.run), 0.15),
        pointBackgroundColor: runColor(s.run),
        fill: true,
        spanGaps: false,
      })),
    },
    options: {
      scales: { r: { min: 0, max: 100, ticks: { stepSize: 20 } } },
      plugins: { legend: { position: "bottom" } },
    },
  });
}

const scatterSets = [];
for (const [run] of data.runs.entries()) {
  for (const setting of settingsSeen) {
    const points = data.episodes.filter((e) => e.run === run && e.setting === setting);
    if (points.length === 0) continue;
    scatterSets.push({
      label: `${label(run)} — ${setting}`,
      data: points.map((e) => ({ x: e.survival, y: e.tracking, episode: e })),
      borderColor: runColor(run),
      backgroundColor: withAlpha(runColor(run), 0.55),
      pointStyle: marker(setting),
      pointRadius: 6,
      pointHoverRadius: 8,
    });
  }
}
draw(data.scatter_id, {
  type: "scatter",
  data: { datasets: scatterSets },
  options: {
    scales: {
      x: { title: { display: true, text: "survival" }, min: 0, max: 1.02 },
      y: { title: { display: true, text: "tracking score 100·exp(−E/σ)" }, min: 0, max: 100 },
    },
    plugins: {
      legend: { position: "bottom" },
      tooltip: {
        callbacks: {
          label: (ctx) => {
            const e = ctx.raw.episode;
            const end = e.termination ? `, ended: ${e.termination}` : "";
            return `${label(e.run)} ${e.setting} ${e.task}/${e.sequence_id}: tracking ${e.tracking.toFixed(1)}, survival ${e.survival.toFixed(2)}, score ${e.score.toFixed(1)}${end}`;
          },
        },
      },
    },
  },
});

for (const plot of data.regimes) {
  const sets = [];
  for (const s of plot.series) {
    sets.push({
      label: `${label(s.run)} — low force`,
      data: s.low,
      backgroundColor: withAlpha(runColor(s.run), 0.45),
      borderColor: runColor(s.run),
      borderWidth: 1,
      stack: `run${s.run}-low`,
    });
    sets.push({
      label: `${label(s.run)} — high force`,
      data: s.high,
      backgroundColor: runColor(s.run),
      borderColor: runColor(s.run),
      borderWidth: 1,
      stack: `run${s.run}-high`,
    });
  }
  draw(plot.id, {
    type: "bar",
    data: { labels: data.tasks, datasets: sets },
    options: {
      scales: { y: { title: { display: true, text: "keypoint RMSE (mm)" }, beginAtZero: true } },
      plugins: { legend: { position: "bottom" } },
    },
  });
}

if (data.latency) {
  const names = ["p50", "p90", "p99", "p99.9", "max"];
  draw(data.latency.percentiles_id, {
    type: "bar",
    data: {
      labels: names,
      datasets: data.latency.series.map((s) => ({
        label: `${label(s.run)} (${s.count} steps, mean ${s.mean_us.toFixed(1)} µs)`,
        data: s.percentiles_us,
        backgroundColor: runColor(s.run),
      })),
    },
    options: {
      scales: { y: { type: "logarithmic", title: { display: true, text: "round trip (µs)" } } },
      plugins: { legend: { position: "bottom" } },
    },
  });
  draw(data.latency.faults_id, {
    type: "bar",
    data: {
      labels: ["deadline misses", "late replies", "invalid actions", "policy failures"],
      datasets: data.latency.series.map((s) => ({
        label: label(s.run),
        data: [s.deadline_misses, s.late_replies, s.invalid_actions, s.policy_failures],
        backgroundColor: runColor(s.run),
      })),
    },
    options: {
      scales: { y: { beginAtZero: true, ticks: { precision: 0 }, title: { display: true, text: "control steps" } } },
      plugins: { legend: { position: "bottom" } },
    },
  });
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
