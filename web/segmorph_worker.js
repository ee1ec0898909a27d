// A worker of SegmorphDecoder.useWorkers(): runs one decode at a time and sends the result back, its arrays
// transferred rather than copied.
import { SegmorphDecoder } from './segmorph_decoder.js';

const transferables = (value, list = []) => {
  if (ArrayBuffer.isView(value)) list.push(value.buffer);
  else if (Array.isArray(value)) value.forEach((v) => transferables(v, list));
  else if (value && typeof value === 'object') Object.values(value).forEach((v) => transferables(v, list));
  return [...new Set(list)];
};

self.onmessage = async ({ data }) => {
  try {
    await SegmorphDecoder.ready;
    const result = SegmorphDecoder[data.method](...data.args);
    self.postMessage({ id: data.id, result }, transferables(result));
  } catch (error) {
    self.postMessage({ id: data.id, error: error.message, unsupported: error.unsupported === true });
  }
};
