// Normals that turn with the surface (spec/README.md, "Normals and tangents", as segmorph decode does), in JavaScript,
// for the plugins (three.js, Babylon.js) that expand frames and targets into morph targets: each vertex's
// normal in the base mesh is turned by the smallest rotation taking the area-weighted normal of the surface around it
// in the base to the one in the frame; vertices at the same base position (seams) share that surface.
export class SurfaceNormals {
  constructor(positions, indices, normals) {
    const count = positions.length / 3, keys = new Map();
    this.point = new Uint32Array(count);  // the surface point (welded vertex) of each vertex
    for (let v = 0; v < count; ++v) {
      const key = `${positions[v * 3]},${positions[v * 3 + 1]},${positions[v * 3 + 2]}`;
      if (!keys.has(key)) keys.set(key, keys.size);
      this.point[v] = keys.get(key);
    }
    this.points = keys.size;
    this.indices = indices;
    this.normals = normals;
    this.base = this._surface(positions);
  }

  _surface(positions) {
    const sum = new Float64Array(this.points * 3), index = this.indices;
    for (let t = 0; t + 2 < index.length; t += 3) {
      const a = index[t] * 3, b = index[t + 1] * 3, c = index[t + 2] * 3;
      const ux = positions[b] - positions[a], uy = positions[b + 1] - positions[a + 1], uz = positions[b + 2] - positions[a + 2];
      const vx = positions[c] - positions[a], vy = positions[c + 1] - positions[a + 1], vz = positions[c + 2] - positions[a + 2];
      const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;  // twice the area, outward
      for (const corner of [index[t], index[t + 1], index[t + 2]]) {
        const p = this.point[corner] * 3;
        sum[p] += nx, sum[p + 1] += ny, sum[p + 2] += nz;
      }
    }
    for (let p = 0; p < sum.length; p += 3) {
      const length = Math.hypot(sum[p], sum[p + 1], sum[p + 2]);
      if (length > 0) sum[p] /= length, sum[p + 1] /= length, sum[p + 2] /= length;
    }
    return sum;
  }

  // The base normals turned to `frame` (V × 3 positions): a new Float32Array.
  turned(frame) {
    const now = this._surface(frame), out = new Float32Array(this.normals.length);
    for (let v = 0; v < this.point.length; ++v) {
      const p = this.point[v] * 3;
      const ax = this.base[p], ay = this.base[p + 1], az = this.base[p + 2];
      const bx = now[p], by = now[p + 1], bz = now[p + 2];
      let nx = this.normals[v * 3], ny = this.normals[v * 3 + 1], nz = this.normals[v * 3 + 2];
      // Rodrigues: the rotation taking a to b, about a × b by the angle between them.
      const cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx, cos = ax * bx + ay * by + az * bz;
      if (cos > -0.999999) {
        const k = 1 / (1 + cos), dot = cx * nx + cy * ny + cz * nz;
        const wx = cy * nz - cz * ny, wy = cz * nx - cx * nz, wz = cx * ny - cy * nx;
        nx = nx * cos + wx + cx * dot * k, ny = ny * cos + wy + cy * dot * k, nz = nz * cos + wz + cz * dot * k;
      }
      out[v * 3] = nx, out[v * 3 + 1] = ny, out[v * 3 + 2] = nz;
    }
    return out;
  }
}
