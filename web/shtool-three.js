// shtool's probe grids in three.js (three@0.187.0): loadProbeGrid reads the probes.json and
// probes.bin that `shtool bake-probes --threejs DIR` writes and returns a LightProbeGridWebGL
// whose texture is the file's atlas, ready for scene.add() with no bake at run time.
// The layout is docs/probe-encodings.md's (three's own LightProbeGridWebGL atlas).
//
//   import { loadProbeGrid } from './shtool-three.js';
//   scene.add( await loadProbeGrid( 'DIR/probes.json' ) );
//
// The page needs an import map for 'three' and 'three/addons/' (three's own examples use the
// same two entries). Do not call bake() on a loaded grid: it would bake over the atlas.
import { Data3DTexture, FloatType, LinearFilter, RGBAFormat, REVISION, Vector3 } from 'three';
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
	return grid;

}

async function fetchBytes( url ) {

	const response = await fetch( url );
	if ( ! response.ok ) throw new Error( `shtool probe grid: ${url}: HTTP ${response.status}` );
	return response.arrayBuffer();

}

// Loads DIR/probes.json and its atlas. `options.load(url)` returns a Promise of an
// ArrayBuffer (default: fetch); node, whose fetch reads no file: URL, passes its own.
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
	return probeGridFromData( doc, atlas, jsonUrl.href );

}
