// shtool in three.js (three@0.187.0): the module of `shtool export-web`'s page (the ZH
// shading of a fit-zh glTF under a light rotated on the GPU, below) and of probe grids.
//
// Probe grids: loadProbeGrid reads the probes.json and
// probes.bin that `shtool bake-probes --threejs DIR` writes and returns a LightProbeGridWebGL
// whose texture is the file's atlas, ready for scene.add() with no bake at run time.
// The layout is docs/probe-encodings.md's (three's own LightProbeGridWebGL atlas).
//
//   import { loadProbeGrid } from './shtool-three.js';
//   scene.add( await loadProbeGrid( 'DIR/probes.json' ) );
//
// The page needs an import map for 'three' and 'three/addons/' (three's own examples use the
// same two entries). Do not call bake() on a loaded grid: it would bake over the atlas.
import { BufferAttribute, BufferGeometry, Data3DTexture, DoubleSide, FloatType, LinearFilter, Matrix3, NearestFilter, NoBlending, OrthographicCamera, Points, RGBAFormat, REVISION, Scene, ShaderMaterial, Vector3, Vector4, WebGLRenderTarget } from 'three';
import { LightProbeGridWebGL } from 'three/addons/lighting/LightProbeGridWebGL.js';

// The three.js release whose atlas layout the files follow.
export const THREE_LAYOUT_VERSION = '0.187.0';

// Seven RGBA slots per probe (27 SH numbers and one 0), one padding slice each side.
const SLOTS = 7;

function fail( what, why ) {

	throw new Error( `shtool probe grid ${what}: ${why}` );

}

function vector3( value, what, name ) {

	if ( ! Array.isArray( value ) || value.length !== 3 || ! value.every( ( v ) => typeof v === 'number' && Number.isFinite( v ) ) )
		fail( what, `${name} must be three finite numbers` );
	return new Vector3( value[ 0 ], value[ 1 ], value[ 2 ] );

}

// The number of float32 values of the atlas of a grid of resolution (nx, ny, nz).
export function atlasFloatCount( nx, ny, nz ) {

	return nx * ny * SLOTS * ( nz + 2 ) * 4;

}

// A LightProbeGridWebGL from the parsed probes.json (`doc`) and the bytes of its atlas.
// `what` names the grid in error messages.
export function probeGridFromData( doc, atlasBytes, what = 'probes.json' ) {

	if ( doc === null || typeof doc !== 'object' ) fail( what, 'is not a JSON object' );
	if ( typeof doc.three !== 'string' ) fail( what, '"three" (the three.js version of the layout) is missing' );
	if ( doc.three !== THREE_LAYOUT_VERSION && typeof console !== 'undefined' )
		console.warn( `shtool probe grid ${what}: written for three ${doc.three}, read with the layout of ${THREE_LAYOUT_VERSION}` );
	if ( REVISION !== THREE_LAYOUT_VERSION.split( '.' )[ 1 ] && typeof console !== 'undefined' )
		console.warn( `shtool probe grid ${what}: three r${REVISION} is loaded; the atlas layout is r${THREE_LAYOUT_VERSION.split( '.' )[ 1 ]}'s` );
	const res = doc.resolution;
	if ( ! Array.isArray( res ) || res.length !== 3 || ! res.every( ( n ) => Number.isInteger( n ) && n >= 1 && n <= 4096 ) )
		fail( what, '"resolution" must be three integers in 1..4096' );
	const box = doc.boundingBox;
	if ( box === null || typeof box !== 'object' ) fail( what, '"boundingBox" with "min" and "max" is missing' );
	const min = vector3( box.min, what, 'boundingBox.min' );
	const max = vector3( box.max, what, 'boundingBox.max' );
	if ( ! ( min.x < max.x && min.y < max.y && min.z < max.z ) ) fail( what, 'boundingBox.min must be below boundingBox.max on every axis' );
	const [ nx, ny, nz ] = res;
	if ( ! ( atlasBytes instanceof ArrayBuffer ) ) fail( what, 'the atlas is not an ArrayBuffer' );
	const count = atlasFloatCount( nx, ny, nz );
	if ( atlasBytes.byteLength !== count * 4 )
		fail( what, `the atlas holds ${atlasBytes.byteLength} bytes; resolution ${nx} x ${ny} x ${nz} needs ${count * 4} (float32 RGBA, ${nx} x ${ny} x ${SLOTS * ( nz + 2 )} texels)` );

	// The file is little-endian float32; a big-endian host reads it through a DataView.
	let data;
	if ( new Uint8Array( new Uint16Array( [ 1 ] ).buffer )[ 0 ] === 1 ) {

		data = new Float32Array( atlasBytes );

	} else {

		const view = new DataView( atlasBytes );
		data = new Float32Array( count );
		for ( let i = 0; i < count; i ++ ) data[ i ] = view.getFloat32( 4 * i, true );

	}
	for ( let i = 0; i < count; i ++ ) if ( ! Number.isFinite( data[ i ] ) ) fail( what, `atlas value ${i} is not finite` );

	const size = new Vector3().subVectors( max, min );
	const grid = new LightProbeGridWebGL( size.x, size.y, size.z, nx, ny, nz );
	grid.name = 'shtool probe grid';
	grid.position.addVectors( min, max ).multiplyScalar( 0.5 );
	grid.updateBoundingBox();
	// The file's bounds exactly (centre and size round).
	grid.boundingBox.min.copy( min );
	grid.boundingBox.max.copy( max );

	const texture = new Data3DTexture( data, nx, ny, SLOTS * ( nz + 2 ) );
	texture.format = RGBAFormat;
	texture.type = FloatType;
	texture.minFilter = LinearFilter;
	texture.magFilter = LinearFilter;
	texture.generateMipmaps = false;
	texture.needsUpdate = true;
	grid.texture = texture;
	// three's dispose() frees the atlas only when its own bake made it (a render target):
	// this one is the loader's, freed here with the rest.
	const disposeGrid = grid.dispose.bind( grid );
	grid.dispose = () => {

		if ( grid.texture === texture ) {

			texture.dispose();
			grid.texture = null;

		}
		disposeGrid();

	};
	return grid;

}

// Throws when this WebGL cannot hold the grid's atlas. A 3D texture past
// MAX_3D_TEXTURE_SIZE fails to upload, and three then lights the scene with zeros without
// a word. WebGL2 guarantees 256 texels: 34 probes along three's z (shtool's y), since the
// atlas stacks 7 (nz + 2) slices.
export function checkProbeGridFits( renderer, grid, what = 'probes.json' ) {

	const gl = renderer.getContext();
	const limit = gl.getParameter( gl.MAX_3D_TEXTURE_SIZE );
	const { width, height, depth } = grid.texture.image;
	if ( Math.max( width, height, depth ) > limit )
		fail( what, `its atlas is ${width} x ${height} x ${depth} texels, past this WebGL's MAX_3D_TEXTURE_SIZE ${limit} (WebGL2 guarantees 256: at most 34 probes along three's z, shtool's y)` );

}

async function fetchBytes( url ) {

	const response = await fetch( url );
	if ( ! response.ok ) throw new Error( `shtool probe grid: ${url}: HTTP ${response.status}` );
	return response.arrayBuffer();

}

// Loads DIR/probes.json and its atlas. `options.load(url)` returns a Promise of an
// ArrayBuffer (default: fetch); node, whose fetch reads no file: URL, passes its own.
// `options.renderer`, when given, is checked to hold the atlas (checkProbeGridFits).
export async function loadProbeGrid( url, options = {} ) {

	const load = options.load || fetchBytes;
	const base = typeof document !== 'undefined' ? document.baseURI : ( typeof location !== 'undefined' ? location.href : undefined );
	const jsonUrl = new URL( url, base );
	const text = new TextDecoder().decode( await load( jsonUrl.href ) );
	let doc;
	try {

		doc = JSON.parse( text );

	} catch ( e ) {

		fail( jsonUrl.href, `is not JSON (${e.message})` );

	}
	if ( doc === null || typeof doc !== 'object' || typeof doc.atlas !== 'string' || doc.atlas === '' )
		fail( jsonUrl.href, '"atlas" (the name of the .bin beside it) is missing' );
	const atlas = await load( new URL( doc.atlas, jsonUrl ).href );
	const grid = probeGridFromData( doc, atlas, jsonUrl.href );
	if ( options.renderer ) checkProbeGridFits( options.renderer, grid, jsonUrl.href );
	return grid;

}

// ---------------------------------------------------------------------------------------
// The page of `shtool export-web DIR` (docs/web.md): the mesh of a fit-zh glTF with its ZH
// lobes, shaded by [4] Eq. 13 under an SH light that the generated zxzxz code rotates on
// the GPU once per frame (lightRotationPass), or per vertex where WebGL cannot render to
// float textures.

// The glTF component types the mesh file uses.
const COMPONENTS = { 5121: Uint8Array, 5123: Uint16Array, 5125: Uint32Array, 5126: Float32Array };
const WIDTHS = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };

// A .glb as fit-zh --gltf and export-web write it (one mesh, one TRIANGLES primitive) as a
// BufferGeometry: 'position', the lobes ('zhAxis<k>', 'zhCoeffs<k>_<j>'), 'zhDirect' when
// stored, and the index. Frames are glTF's, as written.
export function zhGeometryFromGlb( bytes, what = 'mesh.glb' ) {

	const view = new DataView( bytes );
	if ( bytes.byteLength < 20 || view.getUint32( 0, true ) !== 0x46546c67 || view.getUint32( 4, true ) !== 2 )
		throw new Error( `${what}: not a binary glTF 2.0 file` );
	const jsonLength = view.getUint32( 12, true );
	if ( view.getUint32( 16, true ) !== 0x4e4f534a ) throw new Error( `${what}: the first chunk is not JSON` );
	const doc = JSON.parse( new TextDecoder().decode( new Uint8Array( bytes, 20, jsonLength ) ) );
	const binStart = 20 + jsonLength + 8;
	const primitive = doc.meshes[ 0 ].primitives[ 0 ];
	const accessor = ( index ) => {

		const a = doc.accessors[ index ];
		const bv = doc.bufferViews[ a.bufferView ];
		const Type = COMPONENTS[ a.componentType ];
		const width = WIDTHS[ a.type ];
		if ( ! Type || ! width || ( bv.byteStride && bv.byteStride !== width * Type.BYTES_PER_ELEMENT ) )
			throw new Error( `${what}: accessor ${index} is not a packed ${a.type}` );
		const offset = binStart + ( bv.byteOffset || 0 ) + ( a.byteOffset || 0 );
		return { array: new Type( bytes.slice( offset, offset + a.count * width * Type.BYTES_PER_ELEMENT ) ), width };

	};
	const geometry = new BufferGeometry();
	const add = ( gltfName, name ) => {

		if ( primitive.attributes[ gltfName ] === undefined ) return false;
		const { array, width } = accessor( primitive.attributes[ gltfName ] );
		geometry.setAttribute( name, new BufferAttribute( array, width ) );
		return true;

	};
	add( 'POSITION', 'position' );
	const extras = doc.meshes[ 0 ].extras || ( doc.asset && doc.asset.extras ) || {};
	let lobes = 0;
	while ( add( `_ZH_AXIS_${lobes}`, `zhAxis${lobes}` ) ) {

		for ( let j = 0; add( `_ZH_COEFFS_${lobes}_${j}`, `zhCoeffs${lobes}_${j}` ); j ++ );
		lobes ++;

	}
	add( '_ZH_DIRECT', 'zhDirect' );
	geometry.setIndex( new BufferAttribute( accessor( primitive.indices ).array, 1 ) );
	geometry.userData.lobes = lobes;
	geometry.userData.extras = extras;
	return geometry;

}

// The light's coefficients for the shaders: channel c's coefficient i at k = c N^2 + i
// of vec4 shtoolLight[ceil(3 N^2 / 4)].
function packedLight( light, order ) {

	const n2 = order * order;
	const packed = new Float32Array( 4 * Math.ceil( 3 * n2 / 4 ) );
	[ 'r', 'g', 'b' ].forEach( ( name, c ) => {

		if ( ! Array.isArray( light[ name ] ) || light[ name ].length !== n2 ) throw new Error( `light.${name} needs ${n2} coefficients` );
		packed.set( light[ name ], c * n2 );

	} );
	const vectors = [];
	for ( let i = 0; i < packed.length; i += 4 ) vectors.push( new Vector4( packed[ i ], packed[ i + 1 ], packed[ i + 2 ], packed[ i + 3 ] ) );
	return vectors;

}

// GLSL that reads channel c of the light uniform into f.
function lightUniformLines( order ) {

	return [
		'uniform mat3 shtoolLightRotation;',
		`uniform vec4 shtoolLight[${Math.ceil( 3 * order * order / 4 )}];`,
		'void shtool_light_channel(int c, out float f[SHTOOL_ORDER * SHTOOL_ORDER]) {',
		'  for (int i = 0; i < SHTOOL_ORDER * SHTOOL_ORDER; ++i) {',
		'    int k = c * SHTOOL_ORDER * SHTOOL_ORDER + i;',
		'    f[i] = shtoolLight[k / 4][k - 4 * (k / 4)];',
		'  }',
		'}' ].join( '\n' );

}

// The once-per-frame rotation: the generated shtool_rotate runs once per colour channel,
// in the vertex shader of one point (gl.POINTS), and the point's fragments write the N^2
// rotated coefficients, which reach them as flat varyings (exact float32), into a float
// RGBA target of 3 ceil(N^2 / 4) x 1 texels: channel c's coefficient i in texel
// c ceil(N^2 / 4) + i / 4, component i % 4. A point of size L covers L texels of the row, so
// one point per channel carries all of them when WebGL passes ceil(N^2 / 4) varying vectors
// (MAX_VARYING_VECTORS, at least 15: orders up to 7 everywhere, 8 where it is 16 or more)
// and draws points that wide (ALIASED_POINT_SIZE_RANGE); otherwise each channel takes the
// fewest points that fit, each running the rotation once and writing its share.
// `limits`: those two, { varyingVectors, pointSize } (rotationPassLimits(renderer)). Needs
// EXT_color_buffer_float (WebGL2 renders to RGBA32F only with it): check
// floatRenderTargets(renderer) first.
export function lightRotationPass( { rotateGlsl, order, light, limits } ) {

	const n2 = order * order;
	const texels = Math.ceil( n2 / 4 );
	const perPoint = Math.max( 1, Math.min( texels, Math.floor( limits.varyingVectors ), Math.floor( limits.pointSize ) ) );
	const points = Math.ceil( texels / perPoint );
	const target = new WebGLRenderTarget( 3 * texels, 1, {
		type: FloatType, format: RGBAFormat, minFilter: NearestFilter, magFilter: NearestFilter,
		depthBuffer: false, stencilBuffer: false, generateMipmaps: false } );
	target.texture.name = 'shtool rotated light';
	const defines = [
		`#define SHTOOL_TEXELS ${texels}`,
		`#define SHTOOL_TEXELS_PER_POINT ${perPoint}`,
		'flat varying vec4 shtoolRotated[SHTOOL_TEXELS_PER_POINT];' ].join( '\n' );
	const vertexShader = [
		rotateGlsl,
		lightUniformLines( order ),
		defines,
		'attribute vec2 shtoolPoint;  // colour channel, first texel of the point within it',
		'void main() {',
		'  int c = int(shtoolPoint.x), first = int(shtoolPoint.y);',
		'  float f[SHTOOL_ORDER * SHTOOL_ORDER];',
		'  float e[SHTOOL_ORDER * SHTOOL_ORDER];',
		'  shtool_light_channel(c, f);',
		'  shtool_rotate(shtoolLightRotation, f, e);',
		'  for (int t = 0; t < SHTOOL_TEXELS_PER_POINT; ++t) {',
		'    vec4 texel = vec4(0.0);',
		'    for (int j = 0; j < 4; ++j) {',
		'      int i = 4 * (first + t) + j;',
		'      if (i < SHTOOL_ORDER * SHTOOL_ORDER) texel[j] = e[i];',
		'    }',
		'    shtoolRotated[t] = texel;',
		'  }',
		'  gl_PointSize = float(min(SHTOOL_TEXELS_PER_POINT, SHTOOL_TEXELS - first));',
		'  gl_Position = vec4(position.xy, 0.0, 1.0);',
		'}' ].join( '\n' );
	const fragmentShader = [
		defines,
		'void main() {',
		'  int x = int(gl_FragCoord.x);',
		'  int i = x - SHTOOL_TEXELS * (x / SHTOOL_TEXELS);  // texel within the channel',
		'  int t = i - SHTOOL_TEXELS_PER_POINT * (i / SHTOOL_TEXELS_PER_POINT);  // within the point',
		'  vec4 texel = vec4(0.0);',
		'  for (int k = 0; k < SHTOOL_TEXELS_PER_POINT; ++k)',
		'    if (k == t) texel = shtoolRotated[k];',
		'  gl_FragColor = texel;',
		'}' ].join( '\n' );
	const material = new ShaderMaterial( {
		uniforms: { shtoolLightRotation: { value: new Matrix3() }, shtoolLight: { value: packedLight( light, order ) } },
		vertexShader,
		fragmentShader,
		blending: NoBlending, depthTest: false, depthWrite: false
	} );
	material.name = 'shtool light rotation';
	// Point k of channel c covers texels c texels + k perPoint .. + its size, centred on
	// them (window x = first texel + size / 2, the single row's centre 0.5).
	const centres = [], starts = [];
	for ( let c = 0; c < 3; c ++ ) {

		for ( let k = 0; k < points; k ++ ) {

			const first = k * perPoint, size = Math.min( perPoint, texels - first );
			centres.push( 2 * ( c * texels + first + size / 2 ) / ( 3 * texels ) - 1, 0, 0 );
			starts.push( c, first );

		}

	}
	const geometry = new BufferGeometry();
	geometry.setAttribute( 'position', new BufferAttribute( new Float32Array( centres ), 3 ) );
	geometry.setAttribute( 'shtoolPoint', new BufferAttribute( new Float32Array( starts ), 2 ) );
	const cloud = new Points( geometry, material );
	cloud.frustumCulled = false;
	const scene = new Scene();
	scene.add( cloud );
	const camera = new OrthographicCamera( - 1, 1, 1, - 1, 0, 1 );
	return {
		texture: target.texture,
		texels,
		// Rotations of one colour channel a frame (1 unless the WebGL limits split it).
		rotationsPerChannel: points,
		texelsPerPoint: perPoint,
		// Rotates the light by R (Matrix3, three's frame) into the texture.
		render( renderer, rotation ) {

			material.uniforms.shtoolLightRotation.value.copy( rotation );
			const previous = renderer.getRenderTarget();
			renderer.setRenderTarget( target );
			renderer.render( scene, camera );
			renderer.setRenderTarget( previous );

		},
		dispose() {

			target.dispose();
			material.dispose();
			geometry.dispose();

		}
	};

}

// The two WebGL limits that decide how many points lightRotationPass draws per channel.
export function rotationPassLimits( renderer ) {

	const gl = renderer.getContext();
	return { varyingVectors: gl.getParameter( gl.MAX_VARYING_VECTORS ), pointSize: gl.getParameter( gl.ALIASED_POINT_SIZE_RANGE )[ 1 ] };

}

// Whether the renderer can draw into the float target of lightRotationPass.
export function floatRenderTargets( renderer ) {

	return renderer.capabilities.isWebGL2 !== false && renderer.extensions.has( 'EXT_color_buffer_float' );

}

// The vertex shader: each lobe's Eq. 13 by the generated shtool_zh_shade on the rotated
// light, plus the coefficients stored directly; the RGB exit radiance goes to the
// fragments, which interpolate it across the triangle (perspective-correct, as render's ray
// barycentrics). The rotated light is read from lightRotationPass's texture when
// `perFrame`; otherwise the light uniform is rotated here by the generated shtool_rotate,
// per vertex and channel.
function zhVertexShader( rotateGlsl, shadeGlsl, order, lobes, direct, perFrame ) {

	const groups = Math.ceil( order / 4 );
	const lines = [];
	for ( let k = 0; k < lobes; k ++ ) {

		lines.push( `attribute vec3 zhAxis${k};` );
		for ( let j = 0; j < groups; j ++ ) lines.push( `attribute vec4 zhCoeffs${k}_${j};` );

	}
	if ( direct ) lines.push( 'attribute vec4 zhDirect;' );
	lines.push( 'varying vec3 vRadiance;' );
	if ( perFrame ) {

		lines.push( shadeGlsl );
		lines.push( 'uniform sampler2D shtoolRotatedLight;' );

	} else {

		lines.push( rotateGlsl, shadeGlsl, lightUniformLines( order ) );

	}
	lines.push( 'void main() {' );
	lines.push( '  vec3 axes[SHTOOL_ZH_LOBES];' );
	lines.push( '  float g[SHTOOL_ZH_LOBES * SHTOOL_ORDER];' );
	for ( let k = 0; k < lobes; k ++ ) {

		lines.push( `  axes[${k}] = zhAxis${k};` );
		for ( let l = 0; l < order; l ++ ) lines.push( `  g[${k * order + l}] = zhCoeffs${k}_${Math.floor( l / 4 )}[${l % 4}];` );

	}
	lines.push( '  float e[SHTOOL_ORDER * SHTOOL_ORDER];' );
	if ( ! perFrame ) lines.push( '  float f[SHTOOL_ORDER * SHTOOL_ORDER];' );
	lines.push( '  for (int c = 0; c < 3; ++c) {' );
	if ( perFrame ) {

		lines.push( '    for (int i = 0; i < SHTOOL_ORDER * SHTOOL_ORDER; ++i)' );
		lines.push( `      e[i] = texelFetch(shtoolRotatedLight, ivec2(${Math.ceil( order * order / 4 )} * c + i / 4, 0), 0)[i - 4 * (i / 4)];` );

	} else {

		lines.push( '    shtool_light_channel(c, f);' );
		lines.push( '    shtool_rotate(shtoolLightRotation, f, e);' );

	}
	lines.push( '    float r = shtool_zh_shade(axes, g, e);' );
	if ( direct ) lines.push( `    r += dot(zhDirect, vec4(e[0], e[1], e[2], e[3]));` );
	lines.push( '    vRadiance[c] = r;' );
	lines.push( '  }' );
	lines.push( '  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);' );
	lines.push( '}' );
	return lines.join( '\n' );

}

// three's own tone mapping and output encoding on the radiance: with ReinhardToneMapping,
// toneMappingExposure 2^E and sRGB output, v 2^E / (1 + v 2^E) then the sRGB curve, the
// curve of render's PNG (negative radiance shown black, as there).
const ZH_FRAGMENT_SHADER = `
varying vec3 vRadiance;
void main() {
  gl_FragColor = vec4(max(vRadiance, vec3(0.0)), 1.0);
  #include <tonemapping_fragment>
  #include <colorspace_fragment>
}`;

// A ShaderMaterial for a zhGeometryFromGlb geometry. With `rotatedLight` (the texture of a
// lightRotationPass of the same order) it shades with the light that pass rotated; without,
// it rotates `light` itself per vertex: `light` holds the RGB coefficients of the scene's
// order in glTF's frame ({r, g, b}) and uniforms.shtoolLightRotation the rotation, a
// Matrix3 in the same frame (g(w) = f(R^-1 w)).
export function zhShadingMaterial( { rotateGlsl, shadeGlsl, order, lobes, direct, light, rotatedLight = null } ) {

	const perFrame = rotatedLight !== null;
	const uniforms = perFrame ? { shtoolRotatedLight: { value: rotatedLight } }
		: { shtoolLightRotation: { value: new Matrix3() }, shtoolLight: { value: packedLight( light, order ) } };
	const material = new ShaderMaterial( {
		uniforms,
		vertexShader: zhVertexShader( rotateGlsl, shadeGlsl, order, lobes, direct, perFrame ),
		fragmentShader: ZH_FRAGMENT_SHADER,
		side: DoubleSide
	} );
	material.name = 'shtool ZH shading';
	return material;

}

// shtool's frame (z up) to glTF's and three's (y up): (x, y, z) -> (x, z, -y).
export const SHTOOL_TO_THREE = new Matrix3().set( 1, 0, 0, 0, 0, 1, 0, - 1, 0 );

// The rotation of a unit quaternion (w, x, y, z; Hamilton, shtool's frame) as a Matrix3 in
// three's frame: C R C^T.
export function lightRotationInThree( w, x, y, z ) {

	const r = new Matrix3().set(
		1 - 2 * ( y * y + z * z ), 2 * ( x * y - w * z ), 2 * ( x * z + w * y ),
		2 * ( x * y + w * z ), 1 - 2 * ( x * x + z * z ), 2 * ( y * z - w * x ),
		2 * ( x * z - w * y ), 2 * ( y * z + w * x ), 1 - 2 * ( x * x + y * y ) );
	const ct = SHTOOL_TO_THREE.clone().transpose();
	return SHTOOL_TO_THREE.clone().multiply( r ).multiply( ct );

}

// The `light-rotation=w,x,y,z` URL parameter as a unit quaternion [w, x, y, z] (identity
// when absent); an Error when it is not four finite numbers of non-zero length.
export function parseLightRotation( text ) {

	if ( text === null || text === undefined ) return [ 1, 0, 0, 0 ];
	const q = text.split( ',' ).map( Number );
	const length = Math.hypot( ...q );
	if ( q.length !== 4 || ! q.every( Number.isFinite ) )
		throw new Error( `light-rotation=${text}: four numbers w,x,y,z of a quaternion are needed` );
	if ( ! ( length > 0 ) ) throw new Error( `light-rotation=${text}: a quaternion of length 0 is no rotation` );
	return q.map( ( v ) => v / length );

}
