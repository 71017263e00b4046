// An MCAP replay of a team mission on the default map, written by `roverplan mission --mcap`, read
// back with @mcap/core's McapIndexedReader (Foxglove's own TypeScript reader: summary, chunk
// indexes, zstd chunks through fzstd, CRCs checked) and counted against the mission's result JSON:
// one pose, fix and telemetry message per 10 Hz sample of each rover, one log message per
// incident, one terrain grid, one scene update. Usage:
//   ROVERPLAN_BIN=build/bin/roverplan node --test tests/mcap/replay.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { McapIndexedReader } from '@mcap/core';
import { decompress } from 'fzstd';

const bin = process.env.ROVERPLAN_BIN;

function readable(bytes) {
  return {
    size: async () => BigInt(bytes.byteLength),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
}

test('roverplan mission --mcap: Foxglove\'s reader finds every channel and message result.json accounts for', async () => {
  assert.ok(bin, 'set ROVERPLAN_BIN to the roverplan binary');
  const dir = mkdtempSync(join(tmpdir(), 'roverplan_mcap_'));
  try {
    const dem = join(dir, 'default.tif'), mcap = join(dir, 'replay.mcap');
    execFileSync(bin, ['terrain', '--out', dem], { stdio: 'ignore' });
    // A short team mission (8 targets) on the default map, 5 rovers, fixed seeds.
    const out = execFileSync(bin, ['mission', '--dem', dem, '--rovers', '5', '--random-pdm', '4', '--pdm-seed', '3',
      '--seed', '1', '--targets', '8', '--json', '--mcap', mcap], { maxBuffer: 1 << 30 });
    const result = JSON.parse(out.toString());
    const bytes = new Uint8Array(readFileSync(mcap));

    const reader = await McapIndexedReader.Initialize({
      readable: readable(bytes),
      decompressHandlers: { zstd: (buffer, size) => decompress(buffer, new Uint8Array(Number(size))) },
    });
    const rovers = result.rovers.length;
    assert.equal(rovers, 5);
    // Terrain, scene, incidents; pose, fix (the default map has a CRS) and telemetry per rover.
    const topics = [...reader.channelsById.values()].map((c) => c.topic);
    assert.equal(topics.length, 3 + 3 * rovers);
    for (const t of ['/map/terrain', '/map/scene', '/incidents']) assert.ok(topics.includes(t), t);
    for (const c of reader.channelsById.values()) {
      assert.equal(c.messageEncoding, 'json');
      assert.equal(reader.schemasById.get(c.schemaId).encoding, 'jsonschema');
    }
    const schemaOf = (topic) => {
      const c = [...reader.channelsById.values()].find((x) => x.topic === topic);
      return reader.schemasById.get(c.schemaId).name;
    };
    assert.equal(schemaOf('/rover_0/pose'), 'foxglove.PoseInFrame');
    assert.equal(schemaOf('/rover_0/fix'), 'foxglove.LocationFix');
    assert.equal(schemaOf('/map/terrain'), 'foxglove.Grid');
    assert.equal(schemaOf('/map/scene'), 'foxglove.SceneUpdate');
    assert.equal(schemaOf('/incidents'), 'foxglove.Log');

    const counts = new Map();
    let last = -1n, total = 0;
    const decoder = new TextDecoder();
    let grid = null, scene = null;
    for await (const m of reader.readMessages()) {
      const topic = reader.channelsById.get(m.channelId).topic;
      counts.set(topic, (counts.get(topic) ?? 0) + 1);
      assert.ok(m.logTime >= last, 'messages come in log time order');
      assert.equal(m.publishTime, m.logTime);
      last = m.logTime;
      total++;
      if (topic === '/map/terrain') grid = JSON.parse(decoder.decode(m.data));
      if (topic === '/map/scene') scene = JSON.parse(decoder.decode(m.data));
    }
    // Counts against result.json: a rover's `samples` metric is its 10 Hz samples.
    for (const r of result.rovers) {
      const samples = r.metrics.samples;
      assert.ok(samples > 0);
      for (const ch of ['pose', 'fix', 'telemetry']) assert.equal(counts.get(`/rover_${r.rover}/${ch}`), samples, `rover ${r.rover} ${ch}`);
    }
    assert.equal(counts.get('/incidents') ?? 0, result.incidents.length);
    assert.equal(counts.get('/map/terrain'), 1);
    assert.equal(counts.get('/map/scene'), 1);
    assert.equal(reader.statistics.messageCount, BigInt(total));
    // The last message is at the end of the mission clock.
    assert.ok(Math.abs(Number(last) / 1e9 - Math.max(...result.rovers.map((r) => r.metrics.time_s))) < 1e-6);
    // The terrain grid covers the map; the scene holds the route, a path per rover and the targets.
    assert.equal(grid.column_count, result.map ? result.map.cols : grid.column_count);
    assert.equal(grid.fields[0].name, 'elevation');
    const ids = scene.entities.map((e) => e.id);
    assert.ok(ids.includes('route') && ids.includes('targets'));
    for (let k = 0; k < rovers; k++) assert.ok(ids.includes(`path_rover_${k}`), `path_rover_${k}`);
    assert.equal(scene.entities.find((e) => e.id === 'targets').spheres.length, result.targets.length);
    console.log(`replay.mcap: ${bytes.byteLength} bytes, ${reader.channelsById.size} channels, ${total} messages, ` +
      `${reader.chunkIndexes.length} chunks`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
