// The meshes of two loaded scenes, for the browser tests' pages (compare.js, gpu.js).

export function meshesOf(object) {
  const list = [];
  object.traverse((o) => { if (o.isMesh) list.push(o); });
  return list;
}

// Pairs each mesh of `a` with one of `b`: the same name and vertex count, else the next unused one with the count.
export function pairs(a, b) {
  const used = new Set(), out = [];
  for (const mesh of a) {
    const count = mesh.geometry.getAttribute('position').count;
    const candidates = b.filter((m) => !used.has(m) && m.geometry.getAttribute('position').count === count);
    const match = candidates.find((m) => m.name === mesh.name) ?? candidates[0];
    if (!match) throw new Error(`no mesh of the decoded file has ${count} vertices like ${mesh.name}`);
    used.add(match);
    out.push([mesh, match]);
  }
  return out;
}
