// What the GPU playback of a version-4 model (docs/runtime.md, "Playing the model") does the same way in the three.js
// and Babylon.js plugins: the parameters blended by the frames' influences, the layout of its textures and the surface
// around each vertex for its normals.

// GLSL (ES 3.0) of texel i of a texture read in rows, as every texture of the GPU playback is.
export const TEXEL_GLSL = /* glsl */`
vec4 segmorphTexel( highp sampler2D map, int i ) {
	int width = textureSize( map, 0 ).x;
	return texelFetch( map, ivec2( i % width, i / width ), 0 );
}
`;

// GLSL (ES 3.0, after TEXEL_GLSL) of the model's evaluation, in the C API's float32 arithmetic and order
// (segmorph_decoder_model_evaluate): segmorphEvaluate(x, clusters, weights, offset) is the position of a vertex at
// base position x with its 4 (cluster, weight) pairs, its own cluster first, and its first coefficient vector at
// texel `offset`. The caller declares the samplers: segmorphParameters (cluster k's [A | t] rows at texels 3k .. 3k + 2,
// then the basis values 4 to a texel), segmorphClusters (row k: its centroid, then (first basis value, m_k)) and
// segmorphCoefficients (the coefficient vectors).
export const MODEL_GLSL = /* glsl */`
vec3 segmorphEvaluate( vec3 x, ivec4 clusters, vec4 weights, int offset ) {
	vec3 p = vec3( 0.0 );
	for ( int j = 0; j < 4; ++ j ) {
		float omega = weights[ j ];
		if ( omega == 0.0 ) continue;
		int k = clusters[ j ];
		vec3 d = x - texelFetch( segmorphClusters, ivec2( 0, k ), 0 ).xyz;
		vec4 r0 = segmorphTexel( segmorphParameters, k * 3 );
		vec4 r1 = segmorphTexel( segmorphParameters, k * 3 + 1 );
		vec4 r2 = segmorphTexel( segmorphParameters, k * 3 + 2 );
		vec3 y = vec3( ( ( r0.x * d.x + r0.y * d.y ) + r0.z * d.z ) + r0.w,
		               ( ( r1.x * d.x + r1.y * d.y ) + r1.z * d.z ) + r1.w,
		               ( ( r2.x * d.x + r2.y * d.y ) + r2.z * d.z ) + r2.w );
		p = p + omega * y;
	}
	ivec2 basis = ivec2( texelFetch( segmorphClusters, ivec2( 1, clusters.x ), 0 ).xy );
	int values = 3 * textureSize( segmorphClusters, 0 ).y;
	vec3 r = vec3( 0.0 );
	for ( int i = 0; i < basis.y; ++ i ) {
		int v = basis.x + i;
		float b = segmorphTexel( segmorphParameters, values + ( v >> 2 ) )[ v & 3 ];
		r = r + segmorphTexel( segmorphCoefficients, offset + i ).xyz * b;
	}
	return p + r;
}
`;

// GLSL (ES 3.0, after TEXEL_GLSL) of normals that turn with the surface, as segmorph decode turns them (the decoder's
// turn_normals):
// segmorphTurn(n, surface, first, count) is n turned by the smallest rotation taking `surface` (the base surface
// normal around the vertex's point) to today's, the normalized sum of the cross products of the `count` triangles
// from entry `first` of segmorphTriangles (each a texel of three vertex indices) at today's positions, texels of
// segmorphShape. The caller declares both samplers.
export const TURN_GLSL = /* glsl */`
vec3 segmorphTurn( vec3 n, vec3 surface, int first, int count ) {
	vec3 now = vec3( 0.0 );
	for ( int i = 0; i < count; ++ i ) {
		ivec3 t = ivec3( segmorphTexel( segmorphTriangles, first + i ).xyz );
		vec3 a = segmorphTexel( segmorphShape, t.x ).xyz;
		now += cross( segmorphTexel( segmorphShape, t.y ).xyz - a, segmorphTexel( segmorphShape, t.z ).xyz - a );
	}
	float size = length( now );
	if ( size > 0.0 ) now /= size;
	vec3 c = cross( surface, now );
	float cosine = dot( surface, now );
	if ( cosine > -0.999999 ) n = n * cosine + cross( c, n ) + c * ( dot( c, n ) / ( 1.0 + cosine ) );
	return n;
}
`;

// The parameters at `influences` (one weight per frame of `model`): Σ w_f P_f + (1 − Σ w_f) P_0 (frame 0 of clip 0
// takes what the weights leave, as absolute morph targets do), in double, into `out` (K × 12 motion floats, then N
// basis values). Exact as a blend of positions, since positions are linear in the parameters.
export function blendParameters(model, influences, out) {
  const { clusterCount: K, basisCount: N, motion, basis } = model, M = K * 12;
  const sum = new Float64Array(M + N);
  let rest = 1;
  const add = (f, w) => {
    for (let i = 0; i < M; ++i) sum[i] += w * motion[f * M + i];
    for (let i = 0; i < N; ++i) sum[M + i] += w * basis[f * N + i];
  };
  for (let f = 0; f < influences.length; ++f) {
    const w = influences[f];
    if (w === 0) continue;
    add(f, w);
    rest -= w;
  }
  if (rest !== 0) add(0, rest);
  for (let i = 0; i < M + N; ++i) out[i] = sum[i];
  return out;
}

// The width of a texture that holds `count` texels in rows: a power of two near the square's side.
export function textureWidth(count) {
  let width = 1;
  while (width * width < count) width *= 2;
  return width;
}

// The surface around each vertex's point, for the shaders that turn normals as the decoder's turn_normals does: per
// vertex its point's base surface normal (model.surface) and (first, count) of its triangles, and the triangles of
// every point in a list, each entry `stride` floats (its three vertex indices, then zeros). A point is a welded vertex
// of the stream (model.welded: vertices whose positions are equal in every frame).
export function surfaceRings(model, indices, stride) {
  const point = model.welded, points = model.weldedCount, first = new Uint32Array(points + 1);
  for (let i = 0; i + 2 < indices.length; i += 3) for (let j = 0; j < 3; ++j) first[point[indices[i + j]] + 1] += 1;
  for (let p = 0; p < points; ++p) first[p + 1] += first[p];
  const at = first.slice(0, points), list = new Float32Array(first[points] * stride);
  for (let i = 0; i + 2 < indices.length; i += 3)
    for (let j = 0; j < 3; ++j) {
      const e = at[point[indices[i + j]]]++;
      list[e * stride] = indices[i], list[e * stride + 1] = indices[i + 1], list[e * stride + 2] = indices[i + 2];
    }
  const ring = new Uint32Array(point.length * 2);
  for (let v = 0; v < point.length; ++v) {
    ring[v * 2] = first[point[v]];
    ring[v * 2 + 1] = first[point[v] + 1] - first[point[v]];
  }
  return { surface: model.surface, ring, list, entries: first[points] };
}
