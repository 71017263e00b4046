// Keep-out zones as the editor holds them ({ring (open), name, id, version}, local frame) and
// as GeoJSON (closed rings, the id and version the server gave), with their area and hit test.

export function area(ring) {
  let a = 0;
  for (let i = 0, j = ring.length - 1; i < ring.length; j = i++) a += ring[j][0] * ring[i][1] - ring[i][0] * ring[j][1];
  return Math.abs(a) / 2;
}

export function inside(ring, x, y) {
  let c = false;
  for (let i = 0, j = ring.length - 1; i < ring.length; j = i++) {
    const [xi, yi] = ring[i], [xj, yj] = ring[j];
    if ((yi > y) !== (yj > y) && x < ((xj - xi) * (y - yi)) / (yj - yi) + xi) c = !c;
  }
  return c;
}

// GeoJSON rings are closed (first position repeated); the editor keeps them open.
export function zonesToGeoJson(zones) {
  return {
    type: 'FeatureCollection',
    features: zones.map((z) => ({
      type: 'Feature',
      ...(z.id ? { id: z.id } : {}),
      properties: z.name ? { name: z.name } : {},
      geometry: { type: 'Polygon', coordinates: [[...z.ring, z.ring[0]].map(([x, y]) => [x, y])] },
    })),
  };
}

export function zonesFromGeoJson(fc) {
  return (fc?.features || []).map((f) => {
    const ring = f.geometry.coordinates[0].slice(0, -1).map(([x, y]) => [x, y]);
    return { ring, name: f.properties?.name || '', id: typeof f.id === 'string' ? f.id : '', version: f.properties?.version ?? 0 };
  });
}
