// Renaming a map or a study in place (issue 26). The name becomes an input: Enter saves it with
// the version it was read at (If-Match), Escape or leaving it keeps the old one (as a run's
// label). When someone renamed it meanwhile the server answers 412 with the current object: the row then says who
// renamed it to what, and offers keep mine (saved again, naming their version) or take theirs.
// Who: the last "changed" event of that object on the live stream (live_sync.js notes it here).

import { el, report } from './util.js';

const changedBy = new Map();  // `${object}:${id}` -> the operator of its last change

// Called for every event of the live stream.
export function noteChange(e) {
  if (e.kind === 'changed' && e.by) changedBy.set(`${e.object}:${e.id}`, e.by);
}

// o: {row (the list item), object ('map' | 'study'), id, name, version, what ('map', 'study'),
//     save(name, version) -> the object saved, done(object | null)} — done(null): nothing changed.
export function editName(o) {
  const nameButton = o.row.querySelector('button.name');
  const input = el('input', { type: 'text', value: o.name, maxlength: '200', class: 'rename', 'aria-label': `new name of ${o.what} ${o.name}` });
  let finished = false;
  const finish = async (save) => {
    if (finished) return;
    finished = true;
    const name = input.value.trim();
    if (!save || name === '' || name === o.name) {
      o.done(null);
      return;
    }
    await attempt(o, name, o.version, input);
  };
  input.addEventListener('keydown', (e) => {
    if (e.key === 'Enter') finish(true);
    else if (e.key === 'Escape') finish(false);
  });
  input.addEventListener('blur', () => finish(false));
  (nameButton || o.row.firstChild).replaceWith(input);
  input.focus();
  input.select();
}

async function attempt(o, name, version, anchor) {
  try {
    o.done(await o.save(name, version));
  } catch (err) {
    if (err.code === 'version_conflict' && err.current) conflict(o, name, err.current, anchor);
    else {
      report(err);
      o.done(null);
    }
  }
}

// Both names side by side; nothing is saved until one is chosen.
function conflict(o, mine, theirs, anchor) {
  const by = changedBy.get(`${o.object}:${o.id}`) || 'another operator';
  const box = el('div', { class: 'name-conflict', role: 'alert', dataset: { object: o.object, id: o.id } },
    el('div', {}, `⚠ ${by} renamed this ${o.what} to “${theirs.name}” (v${theirs.version}) after you opened it; yours: “${mine}”. Nothing was overwritten.`),
    el('div', { class: 'form-row' },
      el('button', { class: 'keep-mine', title: `rename it to “${mine}” over theirs`, onclick: () => attempt(o, mine, theirs.version, box) }, 'keep mine'),
      el('button', { class: 'take-theirs', title: `keep “${theirs.name}”`, onclick: () => o.done(theirs) }, 'take theirs')),
  );
  if (anchor.isConnected) anchor.replaceWith(box);
  else o.row.append(box);
  box.querySelector('button.keep-mine').focus();
}
