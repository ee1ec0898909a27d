// A small SVG chart writer for the benchmark harness: line charts with linear or logarithmic axes, and
// horizontal stacked bars. No dependencies; the output is a standalone SVG file that GitHub renders.
//
//   lineChart({ title, x: { label, log }, y: { label, log }, series, references, width, height, legendWidth })
//     series:     [{ name, points: [[x, y], ...], dashed?, markersOnly? }]; points with a non-positive value on
//                 a log axis, or a non-finite one, are left out (the legend says how many)
//     references: [{ name, y }]: a horizontal dashed line across the chart (e.g. a lossless size)
//   barChart({ title, x: { label }, categories, stacks, marks, width }) -> string
//     categories: row labels, top to bottom; stacks: [{ name, values: [per category] }] drawn end to end;
//     marks: [{ name, values }]: a tick at that value on each row (e.g. another tool's total)
//   panels([svg, ...], columns) -> string: charts side by side in one file

const PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f',
                 '#bcbd22', '#17becf', '#393b79', '#637939'];
const FONT = 'font-family="Helvetica,Arial,sans-serif"';

const escape = (text) => String(text).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
const round = (x) => Math.round(x * 10) / 10;

function tickLabel(value) {
  if (value === 0) return '0';
  const magnitude = Math.abs(value);
  if (magnitude >= 1e5 || magnitude < 1e-3) return value.toExponential(0).replace('e+', 'e');
  return String(Number(value.toPrecision(3)));
}

// The nearest 1-2-5 step (1, 2, 5, 10, 20, ...) at or below `v` (direction -1) or at or above it (+1).
function step125(v, direction) {
  const decade = 10 ** Math.floor(Math.log10(v));
  const candidates = [1, 2, 5, 10].map((m) => m * decade);
  return direction < 0 ? [...candidates].reverse().find((c) => c <= v * (1 + 1e-9))
                       : candidates.find((c) => c >= v * (1 - 1e-9));
}

// The axis mapping and its ticks. A log axis spans whole 1-2-5 steps around the data (ticks at 1-2-5, 1-3 or
// whole decades as the span grows); a linear one "nice" steps from 0 when the data is positive.
function axis(values, { log = false } = {}, length) {
  let low = Math.min(...values), high = Math.max(...values);
  if (log) {
    low = step125(low / 1.12, -1);  // a margin, so that no point sits on the frame
    high = step125(high * 1.12, +1);
    if (high <= low) high = low * 10;
    const span = Math.log10(high / low);
    const ticks = [];
    for (let d = Math.floor(Math.log10(low)); d <= Math.ceil(Math.log10(high)); d++)
      for (const m of span > 4 ? [1] : span > 2 ? [1, 3] : [1, 2, 5]) {
        const t = m * 10 ** d;
        if (t >= low * (1 - 1e-9) && t <= high * (1 + 1e-9)) ticks.push(Number(t.toPrecision(3)));
      }
    return { map: (v) => (Math.log10(v / low) / span) * length, ticks, accepts: (v) => Number.isFinite(v) && v > 0 };
  }
  if (low > 0 && low < high / 3) low = 0;
  if (high === low) high = low + 1;
  const raw = (high - low) / 6;
  const magnitude = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * magnitude).find((s) => s >= raw);
  low = Math.floor(low / step) * step;
  high = Math.ceil(high / step) * step;
  const ticks = [];
  for (let t = low; t <= high + step / 2; t += step) ticks.push(Number(t.toPrecision(6)));
  return { map: (v) => ((v - low) / (high - low)) * length, ticks, accepts: Number.isFinite };
}

function frame(width, height, body) {
  return `<svg xmlns="http://www.w3.org/2000/svg" width="${width}" height="${height}" viewBox="0 0 ${width} ${height}" ${FONT} font-size="12">\n` +
         `<rect width="${width}" height="${height}" fill="white"/>\n${body}</svg>\n`;
}

function legend(entries, left, top) {
  return entries.map(({ name, color, dashed, marker }, i) => {
    const y = top + i * 18;
    const line = `<line x1="${left}" y1="${y}" x2="${left + 22}" y2="${y}" stroke="${color}" stroke-width="2"${dashed ? ' stroke-dasharray="5,3"' : ''}/>`;
    const dot = marker ? `<circle cx="${left + 11}" cy="${y}" r="3" fill="${color}"/>` : '';
    return `${line}${dot}<text x="${left + 28}" y="${y + 4}">${escape(name)}</text>`;
  }).join('\n');
}

export function lineChart({ title, x, y, series, references = [], width = 860, height = 440, legendWidth = 290 }) {
  const margin = { left: 64, right: legendWidth + 16, top: 36, bottom: 48 };
  const plotWidth = width - margin.left - margin.right, plotHeight = height - margin.top - margin.bottom;
  const xs = [], ys = [];
  const probeX = axis([1, 10], x, 1), probeY = axis([1, 10], y, 1);
  for (const s of series)
    for (const [px, py] of s.points) if (probeX.accepts(px) && probeY.accepts(py)) xs.push(px), ys.push(py);
  for (const r of references) if (probeY.accepts(r.y)) ys.push(r.y);
  if (xs.length === 0) xs.push(...(x.log ? [0.01, 1] : [0, 1]));
  if (ys.length === 0) ys.push(...(y.log ? [0.1, 10] : [0, 1]));
  const ax = axis(xs, x, plotWidth), ay = axis(ys, y, plotHeight);
  const px = (v) => round(margin.left + ax.map(v)), py = (v) => round(margin.top + plotHeight - ay.map(v));

  const parts = [`<text x="${width / 2}" y="20" text-anchor="middle" font-size="14" font-weight="bold">${escape(title)}</text>`];
  for (const t of ax.ticks)
    parts.push(`<line x1="${px(t)}" y1="${margin.top}" x2="${px(t)}" y2="${margin.top + plotHeight}" stroke="#e6e6e6"/>`,
               `<text x="${px(t)}" y="${margin.top + plotHeight + 16}" text-anchor="middle">${tickLabel(t)}</text>`);
  for (const t of ay.ticks)
    parts.push(`<line x1="${margin.left}" y1="${py(t)}" x2="${margin.left + plotWidth}" y2="${py(t)}" stroke="#e6e6e6"/>`,
               `<text x="${margin.left - 6}" y="${py(t) + 4}" text-anchor="end">${tickLabel(t)}</text>`);
  parts.push(`<rect x="${margin.left}" y="${margin.top}" width="${plotWidth}" height="${plotHeight}" fill="none" stroke="#333"/>`,
             `<text x="${margin.left + plotWidth / 2}" y="${height - 10}" text-anchor="middle">${escape(x.label)}${x.log ? ' (log scale)' : ''}</text>`,
             `<text transform="translate(16 ${margin.top + plotHeight / 2}) rotate(-90)" text-anchor="middle">${escape(y.label)}${y.log ? ' (log scale)' : ''}</text>`);

  const entries = [];
  series.forEach((s, i) => {
    const color = s.color || PALETTE[i % PALETTE.length];
    const kept = s.points.filter(([a, b]) => ax.accepts(a) && ay.accepts(b));
    const points = kept.map(([a, b]) => `${px(a)},${py(b)}`);
    if (points.length > 1 && !s.markersOnly)
      parts.push(`<polyline points="${points.join(' ')}" fill="none" stroke="${color}" stroke-width="1.6"${s.dashed ? ' stroke-dasharray="5,3"' : ''}/>`);
    for (const p of points) {
      const [cx, cy] = p.split(',');
      parts.push(`<circle cx="${cx}" cy="${cy}" r="3.2" fill="${color}"/>`);
    }
    const left = s.points.length - kept.length;
    entries.push({ name: s.name + (left ? ` (${left} off the axes)` : ''), color, dashed: s.dashed, marker: true });
  });
  references.forEach((r, i) => {
    const color = r.color || '#555';
    if (ay.accepts(r.y))
      parts.push(`<line x1="${margin.left}" y1="${py(r.y)}" x2="${margin.left + plotWidth}" y2="${py(r.y)}" stroke="${color}" stroke-width="1.4" stroke-dasharray="6,4"/>`);
    entries.push({ name: r.name, color, dashed: true, marker: false, index: i });
  });
  parts.push(legend(entries, width - legendWidth, margin.top + 8));
  return frame(width, height, parts.join('\n') + '\n');
}

export function barChart({ title, x, categories, stacks, marks = [], width = 760 }) {
  const rowHeight = 22, legendRows = stacks.length + marks.length;
  const labelWidth = Math.min(260, 8 + 7 * Math.max(...categories.map((c) => c.length)));
  const margin = { left: labelWidth, right: 24, top: 36, bottom: 52 + legendRows * 18 };
  const plotWidth = width - margin.left - margin.right, plotHeight = categories.length * rowHeight;
  const height = margin.top + plotHeight + margin.bottom;
  const totals = categories.map((_, i) => stacks.reduce((sum, s) => sum + (s.values[i] || 0), 0));
  const ax = axis([0, ...totals, ...marks.flatMap((m) => m.values.filter(Number.isFinite))], {}, plotWidth);
  const px = (v) => round(margin.left + ax.map(v));

  const parts = [`<text x="${width / 2}" y="20" text-anchor="middle" font-size="14" font-weight="bold">${escape(title)}</text>`];
  for (const t of ax.ticks)
    parts.push(`<line x1="${px(t)}" y1="${margin.top}" x2="${px(t)}" y2="${margin.top + plotHeight}" stroke="#e6e6e6"/>`,
               `<text x="${px(t)}" y="${margin.top + plotHeight + 16}" text-anchor="middle">${tickLabel(t)}</text>`);
  categories.forEach((name, i) => {
    const top = margin.top + i * rowHeight;
    parts.push(`<text x="${margin.left - 6}" y="${top + rowHeight / 2 + 4}" text-anchor="end">${escape(name)}</text>`);
    let at = 0;
    stacks.forEach((s, k) => {
      const value = s.values[i] || 0;
      if (value > 0)
        parts.push(`<rect x="${px(at)}" y="${top + 3}" width="${round(px(at + value) - px(at))}" height="${rowHeight - 6}" fill="${s.color || PALETTE[k % PALETTE.length]}"/>`);
      at += value;
    });
    marks.forEach((m, k) => {
      if (Number.isFinite(m.values[i]))
        parts.push(`<line x1="${px(m.values[i])}" y1="${top}" x2="${px(m.values[i])}" y2="${top + rowHeight}" stroke="${m.color || '#000'}" stroke-width="2.5"${k % 2 ? ' stroke-dasharray="3,2"' : ''}/>`);
    });
  });
  parts.push(`<rect x="${margin.left}" y="${margin.top}" width="${plotWidth}" height="${plotHeight}" fill="none" stroke="#333"/>`,
             `<text x="${margin.left + plotWidth / 2}" y="${margin.top + plotHeight + 36}" text-anchor="middle">${escape(x.label)}</text>`);
  const entries = [...stacks.map((s, k) => ({ name: s.name, color: s.color || PALETTE[k % PALETTE.length] })),
                   ...marks.map((m, k) => ({ name: m.name, color: m.color || '#000', dashed: k % 2 === 1 }))];
  parts.push(entries.map(({ name, color, dashed }, k) => {
    const top = margin.top + plotHeight + 50 + k * 18;
    const swatch = k < stacks.length
      ? `<rect x="${margin.left}" y="${top - 6}" width="22" height="12" fill="${color}"/>`
      : `<line x1="${margin.left + 11}" y1="${top - 8}" x2="${margin.left + 11}" y2="${top + 8}" stroke="${color}" stroke-width="2.5"${dashed ? ' stroke-dasharray="3,2"' : ''}/>`;
    return `${swatch}<text x="${margin.left + 28}" y="${top + 4}">${escape(name)}</text>`;
  }).join('\n'));
  return frame(width, height, parts.join('\n') + '\n');
}

// Charts (each a whole SVG document from lineChart or barChart) side by side, `columns` to a row.
export function panels(charts, columns = 2) {
  const sizes = charts.map((svg) => svg.match(/width="(\d+)" height="(\d+)"/).slice(1).map(Number));
  const cellWidth = Math.max(...sizes.map((s) => s[0])), cellHeight = Math.max(...sizes.map((s) => s[1]));
  const rows = Math.ceil(charts.length / columns);
  const width = cellWidth * Math.min(columns, charts.length), height = cellHeight * rows;
  const body = charts.map((svg, i) => {
    const inner = svg.replace(/^<svg [^>]*>\n/, '').replace(/<\/svg>\n?$/, '');
    return `<g transform="translate(${(i % columns) * cellWidth} ${Math.floor(i / columns) * cellHeight})">\n${inner}</g>`;
  }).join('\n');
  return frame(width, height, body + '\n');
}
