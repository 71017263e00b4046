// Incidents and time (issue 13): a small team mission on the default map with a tight exceedance
// limit (so it has incidents) is run from the page; the dock lists as many incidents as
// result.json holds; choosing one (list row, clock mark, map marker) seeks the replay to its time
// and centres the map on it; the mission clock plays in mission seconds at the chosen speed; the
// roll/pitch/speed/energy charts follow the cursor and a click on one seeks; nothing overlaps.
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { test } from 'node:test';
import { mapPoint, openPage, postJson, repoRoot, screenshot, suiteWithServer, waitEnded, waitForMap } from './lib/harness.mjs';

const shotsDir = process.env.ROVERPLAN_SHOTS || join(repoRoot, '..', 'shots');

async function shot(page, name) {
  await screenshot(page, name);
  try {
    mkdirSync(shotsDir, { recursive: true });
    await page.screenshot({ path: join(shotsDir, `${name}.png`) });
  } catch { /* the artifacts copy is enough */ }
}

const state = (page) => page.evaluate(() => {
  const mv = window.__roverplanApp.missionView;
  const v = window.__roverplanApp.view;
  return {
    time: window.__roverplan.replayTime, cursor: mv.cursor, slider: Number(document.getElementById('replay-slider').value),
    playing: mv.replay.playing, selected: mv.incidents.selected, centre: [v.cx, v.cy],
  };
});

// Clicks an incident's row, opening its group first when the group is closed.
async function clickIncident(page, index) {
  const row = page.locator(`#incident-list tr[data-incident="${index}"]`);
  if (await row.isHidden()) {
    const key = await row.getAttribute('data-group');
    await page.$$eval('#incident-list tr.incident-group', (rows, k) => rows.find((r) => r.dataset.group === k).click(), key);
  }
  await row.click();
}

// The page's groups of incidents: kind and cause (result.json `cause`).
function groupsOf(incidents) {
  const g = new Map();
  for (const [i, inc] of incidents.entries()) {
    const key = `${inc.kind}|${inc.cause}`;
    if (!g.has(key)) g.set(key, []);
    g.get(key).push(i);
  }
  return g;
}

function boxesOverlap(a, b) {
  return a.x < b.x + b.width - 0.5 && b.x < a.x + a.width - 0.5 && a.y < b.y + b.height - 0.5 && b.y < a.y + a.height - 0.5;
}

suiteWithServer('incidents and the mission clock', { timeout: 300000 }, (ctx) => {
  let page, context, errors, result, teamPlanner;

  test('a team mission with incidents: the list holds as many as result.json', async (t) => {
    const planners = await (await fetch(`${ctx.server.url}/api/planners`)).json();
    teamPlanner = planners.map((p) => p.name).find((n) => n === 'team-search') || null;
    if (!teamPlanner) return t.skip('no team-search planner listed');
    ({ page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/`));
    await waitForMap(page);
    // No mission: the incident list is empty and the clock disabled.
    assert.equal(await page.textContent('#incident-count'), '0');
    assert.ok(await page.isDisabled('#replay-play'));
    await page.click('#tab-mission');
    await page.selectOption('#m-planner', teamPlanner);
    await page.fill('#m-rover-count', '2');
    await page.dispatchEvent('#m-rover-count', 'input');
    for (const [x, y] of [[40, 40], [46, 40]]) {
      const p = await mapPoint(page, x, y);
      await page.mouse.click(p.x, p.y);
    }
    await page.fill('#m-param-targets', '6');
    // Tight limits force incidents on the default map's slopes: legs planned under 5° end short
    // of their targets, and the rovers' samples pass 2°.
    await page.fill('#m-param-attitude_limit', '5');
    await page.fill('#m-param-exceedance_limit', '2');
    await page.fill('#m-pace', '0');
    // Live incidents (issue 27): the stream's incident frames reach the list before the done
    // frame (frames are handled in order, so "no done frame yet" is exact).
    await page.evaluate(() => {
      const inc = window.__roverplanApp.missionView.incidents;
      const live = inc.live.bind(inc);
      window.__liveIncidents = { frames: 0, beforeDone: 0 };
      inc.live = (msg) => {
        window.__liveIncidents.frames++;
        if (window.__roverplan.doneFrames === 0) window.__liveIncidents.beforeDone += msg.incidents.length;
        live(msg);
      };
    });
    await page.click('#m-launch');
    await page.waitForFunction(() => window.__roverplan.doneFrames > 0, null, { timeout: 180000 });
    await page.waitForFunction(() => !document.getElementById('replay-slider').disabled, null, { timeout: 30000 });
    const id = await page.evaluate(() => window.__roverplan.missionId);
    result = await (await fetch(`${ctx.server.url}/api/missions/${id}/result.json`)).json();
    const kinds = {};
    for (const i of result.incidents) kinds[i.kind] = (kinds[i.kind] || 0) + 1;
    console.log(`mission ${id}: ${result.incidents.length} incidents ${JSON.stringify(kinds)}, mission time ${result.metrics.mission_time_s} s`);
    assert.ok(result.incidents.length > 0, 'the tight limit gives incidents');
    assert.ok(kinds.exceedance > 0 && Object.keys(kinds).length > 1, JSON.stringify(kinds));
    const live = await page.evaluate(() => window.__liveIncidents);
    console.log(`live: ${live.frames} incident frames, ${live.beforeDone} incidents before the done frame`);
    assert.ok(live.frames > 0 && live.beforeDone > 0, JSON.stringify(live));
    // Every note names the limit hit with its value and the value reached.
    for (const i of result.incidents.filter((x) => x.kind === 'exceedance'))
      assert.match(i.note, /^\|(roll|pitch)\| reached \d+\.\d\d° over exceedance_limit 2\.0° for \d+ samples$/, i.note);
    // The summary counts each kind.
    for (const [k, n] of Object.entries(kinds)) assert.match(await page.textContent('#incident-summary'), new RegExp(`${k.replace(/_/g, ' ')} ${n}`));
    // Every incident has its time and place.
    for (const i of result.incidents) assert.ok(Number.isFinite(i.time_s) && Number.isFinite(i.x) && Number.isFinite(i.y), JSON.stringify(i));
    assert.equal(Number(await page.textContent('#incident-count')), result.incidents.length);
    await page.click('#dock-tab-incidents');
    assert.equal(await page.locator('#incident-list tr[data-incident]').count(), result.incidents.length);
    // The clock is in mission time: its end is the mission's, its label min:s.
    assert.equal(Number(await page.getAttribute('#replay-slider', 'max')), result.metrics.mission_time_s);
    assert.match(await page.textContent('#replay-label'), /^\d+:\d\d(\.\d)? \/ \d+:\d\d(\.\d)? \(end\)$/);
    // The map layer lists incidents with a legend.
    // A map layer of its own, toggled like the others.
    assert.ok(await page.isChecked('#layer-incidents'));
    await page.uncheck('#layer-incidents');
    assert.equal(await page.evaluate(() => window.__roverplanApp.layers.isVisible('incidents')), false);
    await page.check('#layer-incidents');
  });

  test('incidents are grouped by kind and cause with counts; a group opens; a member seeks the replay', async (t) => {
    if (!result) return t.skip('no team mission');
    await page.click('#dock-tab-incidents');
    const groups = groupsOf(result.incidents);
    const many = [...groups].filter(([, members]) => members.length > 1);
    console.log(`groups: ${[...groups].map(([k, m]) => `${k} ×${m.length}`).join(', ')}`);
    assert.ok(many.length > 0, 'the tight limits give a group of several incidents');
    // One head row per group of several, with its count; its members start hidden.
    assert.equal(await page.locator('#incident-list tr.incident-group').count(), many.length);
    for (const [key, members] of many) {
      const head = page.locator(`#incident-list tr.incident-group[data-group="${key}"]`);
      assert.equal(await head.getAttribute('data-count'), String(members.length));
      assert.match(await head.textContent(), new RegExp(`×${members.length.toLocaleString('en-US')}`));
      assert.equal(await head.getAttribute('aria-expanded'), 'false');
      assert.ok(await page.locator(`#incident-list tr[data-incident="${members[0]}"]`).isHidden());
    }
    // The biggest group opens on a click; a member chosen seeks the replay to its time.
    const [key, members] = many.sort((a, b) => b[1].length - a[1].length)[0];
    const head = page.locator(`#incident-list tr.incident-group[data-group="${key}"]`);
    await head.click();
    assert.equal(await head.getAttribute('aria-expanded'), 'true');
    for (const i of members) assert.ok(await page.locator(`#incident-list tr[data-incident="${i}"]`).isVisible());
    const pick = members[Math.floor(members.length / 2)];
    await page.click(`#incident-list tr[data-incident="${pick}"]`);
    const s = await state(page);
    assert.equal(s.selected, pick);
    assert.ok(Math.abs(s.time - result.incidents[pick].time_s) < 1e-6, `${s.time} vs ${result.incidents[pick].time_s}`);
    await page.waitForTimeout(150);
    await shot(page, 'results-incidents-grouped');
    // Closed again, then a member chosen elsewhere (the API, as the map or clock do) opens it.
    await head.click();
    assert.ok(await page.locator(`#incident-list tr[data-incident="${members[0]}"]`).isHidden());
    await page.evaluate((i) => window.__roverplanApp.missionView.incidents.select(i), members[0]);
    assert.equal(await head.getAttribute('aria-expanded'), 'true');
    assert.ok(await page.locator(`#incident-list tr[data-incident="${members[0]}"]`).isVisible());
  });

  test('choosing an incident seeks the replay to its time and centres the map on it', async (t) => {
    if (!result) return t.skip('no team mission');
    // The latest incident that is not at the end, so the seek is visible.
    const order = result.incidents.map((inc, i) => [inc.time_s, i]).sort((a, b) => a[0] - b[0]);
    const [time, index] = order[Math.floor(order.length / 2)];
    const inc = result.incidents[index];
    await clickIncident(page, index);
    let s = await state(page);
    assert.equal(s.selected, index);
    assert.ok(Math.abs(s.time - time) < 1e-6, `${s.time} vs ${time}`);
    assert.ok(Math.abs(s.slider - time) <= 0.1, `slider ${s.slider} vs ${time}`);
    assert.ok(Math.abs(s.cursor - time) < 1e-6, 'the charts\' cursor is at the incident');
    assert.ok(Math.abs(s.centre[0] - inc.x) < 1e-6 && Math.abs(s.centre[1] - inc.y) < 1e-6, 'map centred on it');
    assert.ok(await page.$eval(`#incident-list tr[data-incident="${index}"]`, (r) => r.classList.contains('selected')));
    await page.waitForTimeout(150);
    await shot(page, 'incidents-list');

    // A marker on the map: another incident, clicked where it is drawn.
    const other = order.find(([, i]) => i !== index && Math.hypot(result.incidents[i].x - inc.x, result.incidents[i].y - inc.y) > 3);
    if (other) {
      const o = result.incidents[other[1]];
      const p = await mapPoint(page, o.x, o.y);
      const hit = await page.evaluate(([x, y]) => {
        const mv = window.__roverplanApp.missionView;
        const r = window.__roverplanApp.view.canvas.getBoundingClientRect();
        return mv.incidents.hit(x - r.left, y - r.top);
      }, [p.x, p.y]);
      await page.mouse.click(p.x, p.y);
      s = await state(page);
      assert.equal(s.selected, hit);
      assert.ok(Math.abs(s.time - result.incidents[hit].time_s) < 1e-6);
    }

    // A mark on the clock's strip: the first incident in time.
    const [t0, i0] = order[0];
    const box = await page.locator('#replay-strip').boundingBox();
    const x = await page.evaluate((tt) => window.__roverplanApp.missionView.replay.stripX(tt, document.getElementById('replay-strip').getBoundingClientRect().width), t0);
    await page.mouse.click(box.x + x, box.y + box.height / 2);
    s = await state(page);
    assert.ok(Math.abs(s.time - result.incidents[s.selected].time_s) < 1e-6);
    assert.ok(Math.abs(result.incidents[s.selected].time_s - t0) < result.metrics.mission_time_s / 50, `${s.selected} vs ${i0}`);
  });

  test('the clock plays in mission seconds at the chosen speed', async (t) => {
    if (!result) return t.skip('no team mission');
    const end = result.metrics.mission_time_s;
    await page.evaluate(() => window.__roverplanApp.missionView.replay.seek(0));
    await page.selectOption('#replay-speed', '10');
    await page.click('#replay-play');
    const w0 = Date.now();
    await page.waitForFunction(() => window.__roverplan.replayTime > 2, null, { timeout: 15000 });
    const slow = (await state(page)).time / ((Date.now() - w0) / 1000);
    assert.ok((await state(page)).playing);
    await page.click('#replay-play');  // pause
    const paused = (await state(page)).time;
    await page.waitForTimeout(300);
    assert.equal((await state(page)).time, paused, 'paused: the clock stands');
    await page.selectOption('#replay-speed', '600');
    const w1 = Date.now();
    await page.click('#replay-play');
    await page.waitForFunction((p) => window.__roverplan.replayTime > p + Math.min(200, (window.__roverplanApp.missionView.replay.end - p) / 2), paused, { timeout: 15000 });
    const fast = ((await state(page)).time - paused) / ((Date.now() - w1) / 1000);
    console.log(`clock: ~${slow.toFixed(1)} mission s per s at 10×, ~${fast.toFixed(0)} at 600× (mission ${end} s)`);
    assert.ok(fast > slow, `600× (${fast}) faster than 10× (${slow})`);
    await page.click('#replay-play');
    // The trails follow the clock: the shown points are the seconds elapsed.
    {
      const { step, time } = await page.evaluate(() => ({ step: window.__roverplan.replayStep, time: window.__roverplan.replayTime }));
      const x = result.rovers.map((r) => result.series[`pitch_deg_rover_${r.rover}`].x).sort((a, b) => b.length - a.length)[0];
      assert.ok(x[step] <= time + 1e-9 && (step + 1 >= x.length || x[step + 1] > time), `step ${step} at ${time} s`);
    }
  });

  test('roll, pitch, speed and energy against time follow the cursor; a click on a chart seeks', async (t) => {
    if (!result) return t.skip('no team mission');
    for (const name of ['roll_deg', 'pitch_deg', 'speed_mps', 'energy_j']) {
      // One series per rover (a rover that never left its start has one point).
      const lengths = result.rovers.map((r) => result.series[`${name}_rover_${r.rover}`]?.x.length ?? 0);
      assert.ok(lengths.every((n) => n >= 1) && Math.max(...lengths) > 2, `${name}: ${lengths}`);
    }
    await page.click('#dock-tab-motion');
    assert.match(await page.textContent('#dock-motion figure:nth-child(1) figcaption'), /roll \(deg\) per second, ±2°/);
    const box = await page.locator('#chart-speed').boundingBox();
    const scale = await page.evaluate(() => document.getElementById('chart-speed').chartScale);
    assert.equal(scale.xMax, result.metrics.mission_time_s);
    await page.mouse.click(box.x + (scale.left + scale.right) / 2, box.y + box.height / 2);
    const s = await state(page);
    assert.ok(Math.abs(s.time - result.metrics.mission_time_s / 2) < result.metrics.mission_time_s / 100, `${s.time}`);
    assert.equal(s.cursor, s.time);
    await page.waitForTimeout(150);
    await shot(page, 'incidents-motion');
    await page.click('#dock-tab-overview');
    await page.waitForTimeout(100);
    await shot(page, 'incidents-overview');
  });

  test('the new dock parts overlap no other panel at 1280×800', async (t) => {
    if (!result) return t.skip('no team mission');
    await page.click('#dock-tab-incidents');
    const boxes = await page.evaluate(() => {
      const box = (sel) => {
        const r = document.querySelector(sel).getBoundingClientRect();
        return { sel, x: r.x, y: r.y, width: r.width, height: r.height };
      };
      return ['.dock-tabs', '#dock-incidents', '.dock-status', '.dock-replay', '.side', '.viewer', '#layers-panel', '#legend-panel',
        '#replay-play', '#replay-speed', '.clock-track', '#replay-label', '#export-geojson', '#export-csv'].map(box);
    });
    const by = Object.fromEntries(boxes.map((b) => [b.sel, b]));
    const pairs = [['.dock-tabs', '.dock-status'], ['.dock-tabs', '.viewer'], ['.dock-tabs', '.side'], ['#dock-incidents', '.dock-status'],
      ['#dock-incidents', '.dock-replay'], ['#dock-incidents', '.side'], ['#dock-incidents', '.viewer'], ['#dock-incidents', '.dock-tabs'],
      ['#layers-panel', '#legend-panel'], ['#replay-speed', '.clock-track'], ['.clock-track', '#replay-label'], ['#replay-label', '#export-geojson'],
      ['#replay-play', '#replay-speed']];
    for (const [a, b] of pairs) assert.ok(!boxesOverlap(by[a], by[b]), `${a} ${JSON.stringify(by[a])} overlaps ${b} ${JSON.stringify(by[b])}`);
    for (const b of boxes) assert.ok(b.x >= 0 && b.y >= 0 && b.x + b.width <= 1280.5 && b.y + b.height <= 800.5, `${b.sel} off the page`);
    // The list's rows are readable: the table is not cut to nothing.
    assert.ok(by['#dock-incidents'].height > 100 && by['#dock-incidents'].width > 400, JSON.stringify(by['#dock-incidents']));
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('a coverage run under localisation error: its bumps listed, a click seeks the replay to the bump\'s step', async () => {
    const maps = await (await fetch(`${ctx.server.url}/api/maps`)).json();
    const m = await postJson(`${ctx.server.url}/api/missions`, {
      map: maps[0].id, planner: 'coverage', pace: 0, rovers: [{ x: 30, y: 40, heading: 0 }],
      params: { odometry_noise: 5, heading_noise: 1, coverage: 0.1 },
    });
    await waitEnded(ctx.server.url, m.id);
    const res = await (await fetch(`${ctx.server.url}/api/missions/${m.id}/result.json`)).json();
    console.log(`coverage ${m.id}: ${res.incidents.length} incidents`);
    assert.ok(res.incidents.length > 0 && res.incidents.every((i) => i.kind === 'bump' && Number.isInteger(i.step)));
    const { page: p2, context: c2, errors: e2 } = await openPage(ctx.browser, `${ctx.server.url}/#mission=${m.id}`);
    await p2.waitForFunction(() => !document.getElementById('replay-slider').disabled, null, { timeout: 30000 });
    assert.equal(Number(await p2.textContent('#incident-count')), res.incidents.length);
    assert.equal(await p2.locator('#incident-list tr[data-incident]').count(), res.incidents.length);
    const k = Math.floor(res.incidents.length / 2);
    await p2.click('#dock-tab-incidents');
    await clickIncident(p2, k);
    assert.equal(await p2.evaluate(() => window.__roverplan.replayStep), res.incidents[k].step);
    assert.match(await p2.textContent('#replay-label'), new RegExp(`^step ${res.incidents[k].step} / `));
    await p2.waitForTimeout(150);
    await shot(p2, 'incidents-coverage-bumps');
    assert.deepEqual(e2, []);
    await c2.close();
  });
});
