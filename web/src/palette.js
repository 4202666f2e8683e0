// Colours of runs, shared by the report's plots: Okabe–Ito, readable with the common
// colour-vision deficiencies and in greyscale print.
const COLORS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442"];

export function runColor(i) {
  return COLORS[i % COLORS.length];
}

export function withAlpha(hex, alpha) {
  const n = parseInt(hex.slice(1), 16);
  return `rgba(${(n >> 16) & 255}, ${(n >> 8) & 255}, ${n & 255}, ${alpha})`;
}
