// Serves `shtool export-web` folders on 127.0.0.1, folder k alone under /k/, and opens a
// page per VIEW in one headless Chromium (WebGL2 on SwiftShader), driven over the DevTools
// protocol on a pipe: waits for document.title 'shtool: ready', then saves the canvas as
// PNG. A request of view k outside /k/, or for a file its folder lacks, is listed. Prints
// one JSON line: {views: [png paths], requests: [...], outside: [...], missing: [...],
// console: [...]} or {error}.
//   node export_web_browser.mjs CHROMIUM OUT_DIR VIEW...
// VIEW: DIR or DIR?QUERY (QUERY e.g. light-rotation=w,x,y,z), then optionally #drag=DX,DY:
// the mouse dragged from the canvas centre by (DX, DY) pixels before the capture,
// #touch-drag=DX,DY: the same drag by a finger (DevTools touch events, which the page sees as
// pointer events of type touch), #no-float-targets: the page's WebGL reports no
// EXT_color_buffer_float (a WebGL that cannot render to float textures), or
// #max-varying-vectors=V: its WebGL reports MAX_VARYING_VECTORS = V, or #shifted-texels: the
// rotation pass broken on purpose (each fragment writes the next texel's coefficients, by
// editing the shader source WebGL receives), a check that the test sees a broken pass. Equal DIRs share a
// folder. Per view: its status line in `status`, the vertex counts of its first 16 gl.POINTS
// draws (the rotation pass, one a frame) in `points`, and the pointerType of each
// pointermove on the canvas during a drag in `pointerTypes`.
import { createServer } from 'node:http';
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { readFile } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { join, resolve, sep } from 'node:path';

const [ chromium, outDir, ...specs ] = process.argv.slice( 2 );
const dirs = [], views = [];
for ( const spec of specs ) {

	const hash = spec.indexOf( '#' );
	const fragment = hash < 0 ? '' : spec.slice( hash + 1 );
	const touch = fragment.startsWith( 'touch-drag=' );
	const drag = fragment.startsWith( 'drag=' ) || touch ? fragment.slice( fragment.indexOf( '=' ) + 1 ).split( ',' ).map( Number ) : null;
	const noFloatTargets = fragment === 'no-float-targets';
	const varyingVectors = fragment.startsWith( 'max-varying-vectors=' ) ? Number( fragment.slice( 20 ) ) : null;
	const shiftedTexels = fragment === 'shifted-texels';
	if ( fragment !== '' && ! drag && ! noFloatTargets && ! varyingVectors && ! shiftedTexels )
		throw new Error( `${spec}: #drag=DX,DY, #touch-drag=DX,DY, #no-float-targets, #max-varying-vectors=V or #shifted-texels` );
	const rest = hash < 0 ? spec : spec.slice( 0, hash );
	const q = rest.indexOf( '?' );
	const dir = resolve( q < 0 ? rest : rest.slice( 0, q ) );
	if ( ! dirs.includes( dir ) ) dirs.push( dir );
	views.push( { folder: dirs.indexOf( dir ), query: q < 0 ? '' : rest.slice( q + 1 ), drag, touch, noFloatTargets, varyingVectors, shiftedTexels } );

}
const types = { '.html': 'text/html', '.js': 'text/javascript', '.json': 'application/json', '.glsl': 'text/plain' };
const served = [], missing = [];

const server = createServer( async ( req, res ) => {

	const path = decodeURIComponent( new URL( req.url, 'http://x' ).pathname );
	served.push( path );
	const k = Number( path.split( '/' )[ 1 ] );
	const root = dirs[ k ];
	const file = root ? resolve( root, '.' + path.slice( path.indexOf( '/', 1 ) ) ) : '';
	if ( ! root || ! file.startsWith( root + sep ) ) {

		missing.push( path );
		res.writeHead( 403 );
		res.end();
		return;

	}
	try {

		const body = await readFile( file );
		res.writeHead( 200, { 'Content-Type': types[ file.slice( file.lastIndexOf( '.' ) ) ] || 'application/octet-stream' } );
		res.end( body );

	} catch {

		missing.push( path );
		res.writeHead( 404 );
		res.end();

	}

} );
await new Promise( ( r ) => server.listen( 0, '127.0.0.1', r ) );
const origin = `http://127.0.0.1:${server.address().port}`;

const profile = mkdtempSync( join( tmpdir(), 'shtool-chromium-' ) );
const browser = spawn( chromium, [ '--headless', '--no-sandbox', '--disable-gpu-sandbox', '--use-angle=swiftshader',
	'--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-first-run', '--disable-extensions',
	'--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-default-browser-check',
	'--force-device-scale-factor=1', `--user-data-dir=${profile}`, '--remote-debugging-pipe', 'about:blank' ],
{ stdio: [ 'ignore', 'ignore', 'pipe', 'pipe', 'pipe' ] } );
let stderr = '';
browser.stderr.on( 'data', ( d ) => { stderr = ( stderr + d ).slice( - 4000 ); } );

// The DevTools protocol on fds 3 (to Chromium) and 4 (from it), messages ended by NUL.
let nextId = 1, buffer = '';
const pending = new Map(), listeners = [];
browser.stdio[ 4 ].on( 'data', ( chunk ) => {

	buffer += chunk.toString( 'utf8' );
	let end;
	while ( ( end = buffer.indexOf( '\0' ) ) >= 0 ) {

		const message = JSON.parse( buffer.slice( 0, end ) );
		buffer = buffer.slice( end + 1 );
		if ( message.id !== undefined && pending.has( message.id ) ) {

			const { resolve: ok, reject } = pending.get( message.id );
			pending.delete( message.id );
			if ( message.error ) reject( new Error( JSON.stringify( message.error ) ) );
			else ok( message.result );

		} else for ( const l of listeners ) l( message );

	}

} );
const send = ( method, params = {}, sessionId ) => new Promise( ( ok, reject ) => {

	const id = nextId ++;
	pending.set( id, { resolve: ok, reject } );
	browser.stdio[ 3 ].write( JSON.stringify( { id, method, params, ...( sessionId ? { sessionId } : {} ) } ) + '\0' );

} );
const sleep = ( ms ) => new Promise( ( r ) => setTimeout( r, ms ) );

const requests = [], outside = [], consoleLines = [];
let current = 0;  // the folder of the view being loaded
const result = { views: [], status: [], points: [], pointerTypes: [] };
const deadline = setTimeout( () => finish( { error: `timed out; chromium said: ${stderr}` } ), 240000 );
function finish( extra ) {

	clearTimeout( deadline );
	Object.assign( result, { requests, outside, missing, served, console: consoleLines }, extra );
	process.stdout.write( JSON.stringify( result ) + '\n' );
	server.close();
	// The profile goes once Chromium has exited (it writes there until then).
	const done = () => {

		try { rmSync( profile, { recursive: true, force: true } ); } catch {}
		process.exit( 0 );

	};
	if ( browser.exitCode !== null || browser.signalCode !== null ) done();
	browser.on( 'exit', () => setTimeout( done, 200 ) );
	setTimeout( done, 5000 );
	try { browser.kill( 'SIGTERM' ); } catch {}

}

try {

	const { targetId } = await send( 'Target.createTarget', { url: 'about:blank' } );
	const { sessionId } = await send( 'Target.attachToTarget', { targetId, flatten: true } );
	listeners.push( ( m ) => {

		if ( m.sessionId !== sessionId ) return;
		if ( m.method === 'Network.requestWillBeSent' ) {

			const url = m.params.request.url;
			requests.push( url );
			if ( ! url.startsWith( `${origin}/${current}/` ) && ! url.startsWith( 'data:' ) && url !== 'about:blank' ) outside.push( url );

		}
		if ( m.method === 'Runtime.consoleAPICalled' )
			consoleLines.push( m.params.args.map( ( a ) => a.value !== undefined ? String( a.value ) : a.description || '' ).join( ' ' ) );
		if ( m.method === 'Runtime.exceptionThrown' ) consoleLines.push( JSON.stringify( m.params.exceptionDetails ) );

	} );
	await send( 'Network.enable', {}, sessionId );
	await send( 'Runtime.enable', {}, sessionId );
	await send( 'Page.enable', {}, sessionId );
	// Hides EXT_color_buffer_float from WebGL2 (getExtension and getSupportedExtensions), as
	// on a WebGL that cannot render to float textures.
	const hideFloatTargets = `{
		const P = WebGL2RenderingContext.prototype, get = P.getExtension, list = P.getSupportedExtensions;
		P.getExtension = function ( name ) { return name === 'EXT_color_buffer_float' ? null : get.call( this, name ); };
		P.getSupportedExtensions = function () { return ( list.call( this ) || [] ).filter( ( n ) => n !== 'EXT_color_buffer_float' ); };
	}`;
	// MAX_VARYING_VECTORS as V, as on a WebGL with fewer varyings.
	const fewVaryings = ( v ) => `{
		const P = WebGL2RenderingContext.prototype, get = P.getParameter;
		P.getParameter = function ( name ) { return name === this.MAX_VARYING_VECTORS ? ${v} : get.call( this, name ); };
	}`;
	// The rotation pass's fragments write the texel after theirs (the shader's own line
	// edited); the edit must be found, or the view would test nothing.
	const shiftTexels = `{
		const P = WebGL2RenderingContext.prototype, source = P.shaderSource;
		window.shtoolShifted = 0;
		P.shaderSource = function ( shader, text ) {
			const edited = text.replace( 'if (k == t) texel = shtoolRotated[k];', 'if (k == (t + 1) % SHTOOL_TEXELS_PER_POINT) texel = shtoolRotated[k];' );
			if ( edited !== text ) window.shtoolShifted ++;
			return source.call( this, shader, edited );
		};
	}`;
	// The vertex count of every gl.POINTS draw (the first few), for every view.
	await send( 'Page.addScriptToEvaluateOnNewDocument', { source: `{
		window.shtoolPointDraws = [];
		const P = WebGL2RenderingContext.prototype, draw = P.drawArrays;
		P.drawArrays = function ( mode, first, count ) {
			if ( mode === this.POINTS && window.shtoolPointDraws.length < 16 ) window.shtoolPointDraws.push( count );
			return draw.call( this, mode, first, count );
		};
	}` }, sessionId );
	const evaluate = async ( expression ) => ( await send( 'Runtime.evaluate', { expression, returnByValue: true }, sessionId ) ).result.value;
	for ( const [ i, { folder, query, drag, touch, noFloatTargets, varyingVectors, shiftedTexels } ] of views.entries() ) {

		current = folder;
		const source = noFloatTargets ? hideFloatTargets : varyingVectors ? fewVaryings( varyingVectors ) : shiftedTexels ? shiftTexels : null;
		const hidden = source ? ( await send( 'Page.addScriptToEvaluateOnNewDocument', { source }, sessionId ) ).identifier : null;
		await send( 'Page.navigate', { url: `${origin}/${folder}/index.html${query ? '?' + query : ''}` }, sessionId );
		let title = '';
		for ( let t = 0; t < 1200; t ++ ) {

			await sleep( 100 );
			title = ( await send( 'Runtime.evaluate', { expression: 'document.title', returnByValue: true }, sessionId ) ).result.value;
			if ( title === 'shtool: ready' || title === 'shtool: error' ) break;

		}
		if ( hidden !== null ) await send( 'Page.removeScriptToEvaluateOnNewDocument', { identifier: hidden }, sessionId );
		if ( title !== 'shtool: ready' ) {

			const text = ( await send( 'Runtime.evaluate', { expression: "document.getElementById('status') && document.getElementById('status').textContent", returnByValue: true }, sessionId ) ).result.value;
			finish( { error: `view ${i} (${query}): title '${title}', status '${text}'` } );

		}
		if ( drag ) {

			const box = ( await send( 'Runtime.evaluate', { expression: "JSON.stringify(document.getElementById('view').getBoundingClientRect())", returnByValue: true }, sessionId ) ).result.value;
			const { x, y, width, height } = JSON.parse( box );
			const [ x0, y0 ] = [ x + width / 2, y + height / 2 ];
			await evaluate( "window.shtoolPointerTypes = []; document.getElementById('view').addEventListener('pointermove', (e) => shtoolPointerTypes.push(e.pointerType))" );
			const steps = [ 1, 2, 3, 4 ].map( ( s ) => [ x0 + drag[ 0 ] * s / 4, y0 + drag[ 1 ] * s / 4 ] );
			if ( touch ) {

				await send( 'Emulation.setTouchEmulationEnabled', { enabled: true, maxTouchPoints: 1 }, sessionId );
				const finger = ( type, points ) => send( 'Input.dispatchTouchEvent', { type, touchPoints: points.map( ( [ x, y ] ) => ( { x, y, id: 1 } ) ) }, sessionId );
				await finger( 'touchStart', [ [ x0, y0 ] ] );
				for ( const p of steps ) await finger( 'touchMove', [ p ] );
				await finger( 'touchEnd', [] );

			} else {

				const mouse = ( type, [ px, py ], buttons ) => send( 'Input.dispatchMouseEvent', { type, x: px, y: py, button: 'left', buttons, clickCount: 1 }, sessionId );
				await mouse( 'mousePressed', [ x0, y0 ], 1 );
				for ( const p of steps ) await mouse( 'mouseMoved', p, 1 );
				await mouse( 'mouseReleased', steps[ 3 ], 0 );

			}
			await sleep( 500 );  // frames drawn with the new rotation
			if ( touch ) await send( 'Emulation.setTouchEmulationEnabled', { enabled: false }, sessionId );

		}
		if ( shiftedTexels && ! await evaluate( 'window.shtoolShifted' ) ) throw new Error( `view ${i}: #shifted-texels found no rotation pass to break` );
		result.status.push( await evaluate( "document.getElementById('status').textContent" ) );
		result.points.push( await evaluate( 'window.shtoolPointDraws' ) );
		result.pointerTypes.push( drag ? await evaluate( 'window.shtoolPointerTypes' ) : [] );
		const url = ( await send( 'Runtime.evaluate', { expression: "document.getElementById('view').toDataURL('image/png')", returnByValue: true }, sessionId ) ).result.value;
		const png = join( outDir, `view-${i}.png` );
		writeFileSync( png, Buffer.from( url.slice( url.indexOf( ',' ) + 1 ), 'base64' ) );
		result.views.push( png );

	}
	finish( {} );

} catch ( e ) {

	finish( { error: `${e && e.stack || e}; chromium said: ${stderr}` } );

}
