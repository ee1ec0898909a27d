// The bytes a page allocates and uploads through WebGL 2, counted by wrapping the context's calls (the viewer, the
// browser tests and benchmarks): allocated: bufferData, texImage2D/3D, texStorage2D/3D, renderbufferStorage;
// uploaded: bufferSubData, texSubImage2D/3D. Every WebGL2 context of the page is counted from install() on.
const FORMAT_CHANNELS = { 0x1903: 1, 0x8227: 2, 0x1907: 3, 0x1908: 4, 0x1902: 1, 0x84f9: 1, 0x8d94: 1, 0x8228: 2,
                          0x8d98: 3, 0x8d99: 4, 0x1909: 1, 0x190a: 2, 0x1906: 1 };
const TYPE_BYTES = { 0x1401: 1, 0x1400: 1, 0x1403: 2, 0x1402: 2, 0x1405: 4, 0x1404: 4, 0x1406: 4, 0x140b: 2,
                     0x8d61: 2, 0x84fa: 4, 0x8368: 4, 0x8033: 2, 0x8034: 2, 0x8363: 2, 0x8c3b: 4, 0x8c3e: 4,
                     0x8dad: 8 };
// Sized internal formats: bytes per texel (those three.js and this project use; others count 4).
const SIZED_BYTES = { 0x8814: 16, 0x8815: 12, 0x8230: 8, 0x822e: 4, 0x881a: 8, 0x881b: 6, 0x822f: 4, 0x822d: 2,
                      0x8058: 4, 0x8c43: 4, 0x8051: 3, 0x8229: 1, 0x822b: 2, 0x8d70: 16, 0x8d71: 12, 0x8d7c: 4,
                      0x81a5: 2, 0x81a6: 4, 0x8cac: 4, 0x88f0: 4, 0x8cad: 8, 0x8d48: 1, 0x8d62: 2, 0x8056: 2,
                      0x8057: 2, 0x8c3a: 4, 0x8c3d: 4, 0x8059: 4, 0x8d7d: 4, 0x8235: 4, 0x8236: 4 };

export const gpuBytes = { allocated: 0, uploaded: 0, calls: 0 };

const pixelBytes = (format, type) => (FORMAT_CHANNELS[format] ?? 4) * (TYPE_BYTES[type] ?? 1);

export function install() {
  const proto = WebGL2RenderingContext.prototype;
  if (proto.segmorphCounted) return gpuBytes;
  proto.segmorphCounted = true;
  const wrap = (name, count) => {
    const original = proto[name];
    proto[name] = function (...args) {
      count(args);
      gpuBytes.calls += 1;
      return original.apply(this, args);
    };
  };
  const size = (data) => (typeof data === 'number' ? data : data?.byteLength ?? 0);
  wrap('bufferData', (a) => { gpuBytes.allocated += size(a[1]); });
  wrap('bufferSubData', (a) => {
    const unit = a[2]?.BYTES_PER_ELEMENT ?? 1;
    gpuBytes.uploaded += a[4] ? a[4] * unit : size(a[2]) - (a[3] ?? 0) * unit;
  });
  // texImage2D(target, level, internalformat, width, height, border, format, type, ...), and the 6-argument form
  // whose source (an image, a bitmap, a canvas, a video frame) gives the size: a glTF file's textures.
  const sourceTexels = (source) => (source?.naturalWidth ?? source?.videoWidth ?? source?.displayWidth ?? source?.width ?? 0) *
    (source?.naturalHeight ?? source?.videoHeight ?? source?.displayHeight ?? source?.height ?? 0);
  wrap('texImage2D', (a) => {
    if (a.length >= 9) gpuBytes.allocated += a[3] * a[4] * pixelBytes(a[6], a[7]);
    else if (a.length === 6) gpuBytes.allocated += sourceTexels(a[5]) * pixelBytes(a[3], a[4]);
  });
  wrap('texImage3D', (a) => { gpuBytes.allocated += a[3] * a[4] * a[5] * pixelBytes(a[7], a[8]); });
  wrap('texStorage2D', (a) => {
    let bytes = 0;
    for (let level = 0, w = a[3], h = a[4]; level < a[1]; ++level, w = Math.max(1, w >> 1), h = Math.max(1, h >> 1))
      bytes += w * h * (SIZED_BYTES[a[2]] ?? 4);
    gpuBytes.allocated += bytes;
  });
  wrap('texStorage3D', (a) => {
    let bytes = 0;
    for (let level = 0, w = a[3], h = a[4]; level < a[1]; ++level, w = Math.max(1, w >> 1), h = Math.max(1, h >> 1))
      bytes += w * h * a[5] * (SIZED_BYTES[a[2]] ?? 4);
    gpuBytes.allocated += bytes;
  });
  wrap('renderbufferStorage', (a) => { gpuBytes.allocated += a[2] * a[3] * (SIZED_BYTES[a[1]] ?? 4); });
  wrap('renderbufferStorageMultisample', (a) => { gpuBytes.allocated += a[1] * a[3] * a[4] * (SIZED_BYTES[a[2]] ?? 4); });
  wrap('texSubImage2D', (a) => {
    if (a.length >= 9) gpuBytes.uploaded += a[4] * a[5] * pixelBytes(a[6], a[7]);
    else if (a.length === 7) gpuBytes.uploaded += sourceTexels(a[6]) * pixelBytes(a[4], a[5]);
  });
  wrap('texSubImage3D', (a) => { if (a.length >= 11) gpuBytes.uploaded += a[5] * a[6] * a[7] * pixelBytes(a[8], a[9]); });
  return gpuBytes;
}

// Frees what a three.js object tree holds on the GPU (geometry, materials, their textures, a segmorph player's
// model), so that the bytes counted for the next file are its own. Uses only the objects' own methods.
export function release(root) {
  root.traverse((object) => {
    if (!object.isMesh) return;
    object.segmorph?.player.dispose([object]);
    object.geometry.dispose();
    for (const material of [object.material, object.customDepthMaterial, object.customDistanceMaterial].flat()) {
      if (!material) continue;
      for (const value of Object.values(material)) if (value?.isTexture) value.dispose();
      material.dispose();
    }
  });
}
