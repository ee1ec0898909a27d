// The glTF side of SEGMORPH_animation_compression that the three.js and Babylon.js plugins share: the extension's
// name, the layout of a coded animation's track stream and the check of a stream's clips against the extension.

export const NAME = 'SEGMORPH_animation_compression';
const PATHS = { translation: 0, rotation: 1, scale: 2 };

// The layout of an animation's track stream (spec/README.md, "Coded tracks"): the distinct input accessors of its coded
// samplers in first-named order, and per sampler its time array, path and component count.
export function trackLayout(json, animation, coded, what) {
  const timeAccessors = [], samplers = [];
  for (const s of coded.samplers ?? []) {
    const sampler = animation.samplers?.[s];
    if (!sampler) throw new Error(`${what}: coded sampler ${s} does not exist`);
    const paths = new Set(animation.channels.filter((c) => c.sampler === s).map((c) => c.target.path));
    const path = paths.size === 1 ? PATHS[[...paths][0]] : undefined;
    if (path === undefined) throw new Error(`${what}: coded sampler ${s} must move translations, rotations or scales alone`);
    const input = json.accessors?.[sampler.input], output = json.accessors?.[sampler.output];
    const components = path === 1 ? 4 : 3;
    if (!input || !output || input.bufferView !== undefined || output.bufferView !== undefined ||
        output.count !== input.count || output.type !== (components === 4 ? 'VEC4' : 'VEC3'))
      throw new Error(`${what}: coded sampler ${s} needs FLOAT accessors without data that agree with its path`);
    let times = timeAccessors.indexOf(sampler.input);
    if (times < 0) times = timeAccessors.push(sampler.input) - 1;
    samplers.push({ times, path, components });
  }
  return { timeAccessors, samplers };
}

export function checkClips(frameCounts, extension, timeCounts, what) {
  if (frameCounts.length !== extension.clips.length)
    throw new Error(`${what}: the stream has ${frameCounts.length} clips, the extension names ${extension.clips.length}`);
  frameCounts.forEach((count, c) => {
    if (timeCounts[c] !== count)
      throw new Error(`${what}: clip ${c} has ${count} frames in the stream and ${timeCounts[c]} times`);
  });
}
