// Small DOM and formatting helpers.

export const $ = (id) => document.getElementById(id);

// el('button', {class: 'x', onclick: fn}, 'text', child...)
export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k.startsWith('on') && typeof v === 'function') node.addEventListener(k.slice(2), v);
    else if (k === 'class') node.className = v;
    else if (k === 'dataset') Object.assign(node.dataset, v);
    else if (k in node && typeof v !== 'string') node[k] = v;
    else node.setAttribute(k, v === true ? '' : v);
  }
  for (const c of children.flat()) {
    if (c === null || c === undefined || c === false) continue;
    node.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return node;
}

// A number for people: a few significant digits, no exponent for everyday sizes.
export function fmt(v, digits = 3) {
  if (v === null || v === undefined) return '—';
  if (typeof v !== 'number') return String(v);
  if (!Number.isFinite(v)) return Number.isNaN(v) ? 'nodata' : String(v);
  if (Number.isInteger(v) && Math.abs(v) < 1e9) return v.toLocaleString('en-US');
  const a = Math.abs(v);
  if (a >= 1e6 || (a > 0 && a < 1e-3)) return v.toExponential(2);
  if (a >= 1000) return v.toLocaleString('en-US', { maximumFractionDigits: 0 });
  return Number(v.toPrecision(digits + (a >= 1 ? 1 : 0))).toString();
}

export function fmtMetres(v) {
  return Number.isFinite(v) ? `${v.toFixed(Math.abs(v) < 100 ? 2 : 1)} m` : '—';
}

// Distinct rover colours (colour-blind friendly first).
export const ROVER_COLOURS = ['#ff4f9a', '#3ad6ff', '#ffd23f', '#9dff5c', '#c08bff', '#ff8a3d', '#ffffff', '#5cffc8'];
export const roverColour = (k) => ROVER_COLOURS[k % ROVER_COLOURS.length];

export function clamp(v, lo, hi) {
  return Math.min(hi, Math.max(lo, v));
}

export function showError(node, err) {
  if (!node) return;
  if (!err) {
    node.hidden = true;
    node.textContent = '';
    return;
  }
  node.hidden = false;
  node.textContent = typeof err === 'string' ? err : err.describe ? err.describe() : String(err.message || err);
}

// Runs an async handler and reports a failure in the status line instead of throwing.
export function reportErrors(fn, onError) {
  return async (...args) => {
    try {
      return await fn(...args);
    } catch (err) {
      (onError || defaultReport)(err);
    }
  };
}

let reporter = (msg) => console.warn(msg);
export function setErrorReporter(fn) {
  reporter = fn;
}
function defaultReport(err) {
  reporter(err && err.describe ? err.describe() : String(err && err.message ? err.message : err));
}
export function report(msg) {
  defaultReport(msg);
}
