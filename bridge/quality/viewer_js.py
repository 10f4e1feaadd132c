"""The script of the report page's 3-D view (three.js, embedded in ``index.html`` by :mod:`.html`).

What the page can do without running the check again, from the data of
:func:`~occsurf.bridge.quality.html.viewer_payload`:

* every indicator of :data:`~occsurf.bridge.quality.html.VIEWER_INDICATORS`, coloured per vertex
  with its common colour scale; zebra stripes and isophotes per pixel in a fragment shader
  (stripe count, the direction the stripes run in the view, isophote count: shader uniforms);
* the draft angle against any of the six axis directions, recomputed per vertex from the normals
  (``asin(n . pull)`` in degrees, :func:`occsurf.algorithms.quality.draft_angle`); the stored values
  are shown for the report's own pull ``+z``;
* the sections with their curvature combs and inflections, and the edges coloured by continuity
  class, as line sets that checkboxes show and hide;
* picking: a click on the model casts a ray (``Vector3.unproject`` of the click at the near and far
  planes, Moller-Trumbore against each face's triangles, bounding spheres first), tints the face
  and marks its row in the faces table; a click on a face row tints that face; a click on an edge
  row flies the view to the edge's worst point and marks it;
* without WebGL (or with ``#no-webgl`` in the page's address, for tests), or where the browser
  cannot inflate gzip (``DecompressionStream``), the canvas and its controls are hidden and the
  overview pictures (PNG) are shown in their place with a note.

The vendored bundle exports only the classes listed in ``static/README.md`` (no ``Raycaster``),
hence the hand-written picking.
"""

from __future__ import annotations

__all__ = ["VIEWER_CSS", "VIEWER_JS"]

#: Styles of the 3-D view, its controls and the picked rows.
VIEWER_CSS = """
#viewer-wrap{position:relative;width:100%;max-width:1100px;height:620px;border:1px solid #ccd;background:#fff}
#viewer{width:100%;height:100%;display:block}
#viewer-ui,#viewer-controls{margin:.4em 0;display:flex;flex-wrap:wrap;gap:.3em 1.2em;align-items:center}
#viewer-controls input[type=number]{width:4em}#viewer-controls fieldset{border:1px solid #dde;padding:1px 6px;margin:0}
#viewer-controls legend{font-size:.85em;color:#557}#viewer-pick{margin:.2em 0;min-height:1.2em}
#legend{position:absolute;right:10px;top:10px;background:rgba(255,255,255,.85);padding:4px 6px;font-size:12px}
#legend canvas{display:block;width:24px;height:240px}#legend .title{max-width:9em}
#edge-key span{display:inline-block;width:1.6em;height:.35em;margin:0 .2em .15em .5em;vertical-align:middle}
#viewer-fallback{max-width:1100px;border:1px dashed #b99;padding:.5em;background:#fffaf5}
.table-scroll{max-height:430px;overflow:auto;display:inline-block;border:1px solid #eef}
.table-scroll thead th{position:sticky;top:0}
tr.picked td{background:#ffd79a !important;font-weight:bold}
#face-table tbody tr,#edge-table tbody tr{cursor:pointer}
@media print{.table-scroll{max-height:none;overflow:visible}#view3d{display:none}}
"""

VIEWER_JS = r"""
(async function(){
const DATA = JSON.parse(document.getElementById('viewer-data').textContent);
const IND = JSON.parse(document.getElementById('viewer-indicators').textContent);
const MAPS = JSON.parse(document.getElementById('viewer-maps').textContent);
const status = document.getElementById('viewer-status');
const pickOut = document.getElementById('viewer-pick');
const canvas = document.getElementById('viewer');
const $ = id => document.getElementById(id);
// the arrays: one gzip block (base64) of byte planes, see html.VIEWER_DATA_LAYOUT
async function inflate(text){
  const b = atob(text); const u = new Uint8Array(b.length); for (let i=0;i<b.length;i++) u[i] = b.charCodeAt(i);
  const s = new Blob([u]).stream().pipeThrough(new DecompressionStream('gzip'));
  return new Uint8Array(await new Response(s).arrayBuffer());
}
let RAW = null;
function dec(ref, T){
  const w = T.BYTES_PER_ELEMENT, n = ref.n, c = ref.columns || 1, m = n / c, b = new Uint8Array(n*w);
  for (let k=0;k<w;k++){ const p = RAW.subarray(ref.at + k*n, ref.at + (k+1)*n); for (let i=0;i<n;i++) b[i*w+k] = p[i]; }
  const U = w === 2 ? new Uint16Array(b.buffer) : new Uint32Array(b.buffer);  // the values' bits
  if (ref.delta) for (let j=0;j<c;j++) for (let i=j*m+1;i<(j+1)*m;i++) U[i] = U[i] + U[i-1];  // stored modulo 2**(8w)
  if (c === 1) return new T(b.buffer);
  const out = new U.constructor(n);
  for (let j=0;j<c;j++) for (let i=0;i<m;i++) out[i*c+j] = U[j*m+i];
  return new T(out.buffer);
}
function cmap(name, t){const c=MAPS[name];if(!c)return [0.78,0.8,0.84];if(!(t>=0))t=0;if(t>1)t=1;const x=t*(c.length-1);const i=Math.min(Math.floor(x),c.length-2);const f=x-i;
  return [0,1,2].map(k=>c[i][k]*(1-f)+c[i+1][k]*f);}
function rows(table){ const t=$(table); return t ? Array.from(t.tBodies[0].rows) : []; }
function markRow(table, row){
  for (const r of rows(table)) r.classList.toggle('picked', r===row);
  if (!row) return;
  const box = row.closest('.table-scroll');  // scroll the table's own box, not the page away from the view
  if (box){ const top = row.offsetTop - box.clientHeight/2; box.scrollTop = Math.max(0, top); }
}
function fallback(why){
  for (const id of ['viewer-wrap','viewer-controls','viewer-indicator']){ const e=$(id); if(e) e.style.display='none'; }
  const fb = $('viewer-fallback'); fb.hidden = false;
  const pics = document.querySelectorAll('#overview .pics figure');
  fb.querySelector('.why').textContent = why + '. ' +
    (pics.length ? 'Shown instead: the overview pictures drawn when the report was written' :
     'No pictures were drawn for this report (occsurf check --pictures none)') +
    '; the faces and edges tables below hold the numbers.';
  const into = fb.querySelector('.pics');
  for (const p of pics){ const c = p.cloneNode(true); for (const i of c.querySelectorAll('img')) i.loading = 'eager'; into.appendChild(c); }
  status.textContent = '3-D view off: ' + why;
  document.body.setAttribute('data-viewer', 'fallback');
}
const NEEDS = 'The interactive 3-D view needs WebGL, which ';
if (/(^|[#&])no-webgl\b/.test(location.hash)){ fallback(NEEDS + 'is turned off by #no-webgl in the address'); return; }
try {  // three.js and the arrays come gzip-compressed; DecompressionStream: Chromium 80, Firefox 113, Safari 16.4
  if (typeof THREE === 'undefined') (0, eval)(new TextDecoder().decode(await inflate($('viewer-three').textContent)));
  RAW = await inflate(DATA.data);
} catch(e){ fallback('The interactive 3-D view could not unpack its data in this browser (' + e.message + ')'); return; }
let renderer;
try { renderer = new THREE.WebGLRenderer({canvas, antialias:true, preserveDrawingBuffer:true}); }
catch(e){ fallback(NEEDS + 'is not available in this browser (' + e.message + ')'); return; }
if (DATA.skipped){ status.textContent = 'The model has ' + DATA.n_vertices + ' mesh vertices: too many for the 3-D view; see the pictures.'; }
const scene = new THREE.Scene(); scene.background = new THREE.Color(0xf4f6fa);
const camera = new THREE.PerspectiveCamera(30, 1, 1e-3, 1e7);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 1.2));
const key = new THREE.DirectionalLight(0xffffff, 1.6); camera.add(key); key.position.set(1,1,2); scene.add(camera);
const group = new THREE.Group(); scene.add(group);
const meshes = [];
// surfaces are pushed back a little so the line sets lying on them are not hidden
const back = {polygonOffset:true, polygonOffsetFactor:1, polygonOffsetUnits:1};
const zebraMat = new THREE.ShaderMaterial(Object.assign({side: THREE.DoubleSide,
  uniforms:{pairs:{value:DATA.zebra_pairs||8.0}, iso:{value:DATA.isophote_pairs||6.0}, mode:{value:0}, axis:{value:new THREE.Vector3(1,0,0)}},
  vertexShader:'varying vec3 vN; varying vec3 vP; void main(){ vec4 p = modelViewMatrix*vec4(position,1.0); vP=p.xyz; vN=normalize(normalMatrix*normal); gl_Position=projectionMatrix*p; }',
  fragmentShader:'uniform float pairs; uniform float iso; uniform int mode; uniform vec3 axis; varying vec3 vN; varying vec3 vP; void main(){ vec3 n=normalize(vN); if(!gl_FrontFacing) n=-n; vec3 d=normalize(vP); '+
   'float s; if(mode==0){ vec3 r=reflect(d,n); s=asin(clamp(dot(r,axis),-1.0,1.0))/3.14159265*2.0*pairs+0.25; } else { s=dot(n, vec3(0.0,0.0,1.0))*iso; } '+
   'float w=fwidth(s); float f=fract(s); float a=smoothstep(0.5-w,0.5+w,f)-smoothstep(1.0-w,1.0,f)+ (f<w? 1.0-smoothstep(0.0,w,f):0.0); '+
   'vec3 c=mix(vec3(0.97), vec3(0.05), clamp(a,0.0,1.0)); gl_FragColor=vec4(c,1.0); }'}, back));
const shadedMat = new THREE.MeshPhongMaterial(Object.assign({vertexColors:true, side:THREE.DoubleSide, shininess:40, specular:0x333333}, back));
const byIndex = {};
for (const f of DATA.faces){
  const g = new THREE.BufferGeometry();
  const N = dec(f.normals, Float32Array);
  g.setAttribute('position', new THREE.BufferAttribute(dec(f.points, Float32Array), 3));
  g.setAttribute('normal', new THREE.BufferAttribute(N, 3));
  g.setIndex(new THREE.BufferAttribute(dec(f.triangles, f.triangles_dtype==='uint16' ? Uint16Array : Uint32Array), 1));
  g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3*f.n), 3));
  g.computeBoundingSphere();
  const vals = {}; for (const k in f.values) vals[k] = dec(f.values[k], Float32Array);
  const m = new THREE.Mesh(g, shadedMat); m.userData = {index: f.index, vals, stored: vals.draft, N}; group.add(m); meshes.push(m);
  byIndex[f.index] = m;
}
// ------------------------------------------------------------------ draft against any pull
const PULL = DATA.pull || [0,0,1];
function setPull(p){
  const same = p[0]===PULL[0] && p[1]===PULL[1] && p[2]===PULL[2];
  for (const m of meshes){
    const N = m.userData.N;
    if (same && m.userData.stored){ m.userData.vals.draft = m.userData.stored; continue; }
    const out = new Float32Array(N.length/3);
    for (let i=0;i<out.length;i++){
      const x=N[3*i], y=N[3*i+1], z=N[3*i+2], len=Math.sqrt(x*x+y*y+z*z);
      out[i] = len < 0.5 ? NaN : Math.asin(Math.max(-1, Math.min(1, (x*p[0]+y*p[1]+z*p[2])/len))) * 180/Math.PI;
    }
    m.userData.vals.draft = out;
  }
}
// ------------------------------------------------------------------ line sets
function segments(pack){
  const P = dec(pack.points, Float32Array), C = dec(pack.counts, Uint32Array);
  let n = 0; for (const c of C) n += Math.max(0, c-1);
  const out = new Float32Array(6*n); let o = 0, s = 0;
  for (const c of C){ for (let j=0;j<c-1;j++){ out.set(P.subarray(3*(s+j), 3*(s+j+2)), o); o += 6; } s += c; }
  return out;
}
function lineSet(pos, rgb){
  const g = new THREE.BufferGeometry(); g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({color: new THREE.Color(rgb[0], rgb[1], rgb[2])}));
}
const box0 = new THREE.Box3().setFromObject(group); const sph = box0.getBoundingSphere(new THREE.Sphere());
const R = sph.radius || 1;
function crosses(P, size){
  const out = new Float32Array(P.length*6); const o = [[1,0,0],[0,1,0],[0,0,1]];
  for (let i=0;i<P.length/3;i++) for (let k=0;k<3;k++) for (let e=0;e<2;e++) for (let j=0;j<3;j++)
    out[18*i+6*k+3*e+j] = P[3*i+j] + (e?1:-1)*size*o[k][j];
  return out;
}
const L = DATA.lines || {};
const sets = {sections: new THREE.Group(), combs: new THREE.Group(), edges: new THREE.Group()};
if (L.sections) sets.sections.add(lineSet(segments(L.sections), [0.1,0.1,0.5]));
if (L.combs) sets.combs.add(lineSet(segments(L.combs), [0.85,0.25,0.1]));
if (L.inflections) sets.combs.add(lineSet(crosses(dec(L.inflections, Float32Array), R*0.012), [0,0.6,0]));
for (const e of (L.edges || [])) sets.edges.add(lineSet(segments(e), e.color));
RAW = null;  // every array is decoded: the block can go
for (const k in sets){ sets[k].visible = false; scene.add(sets[k]);
  const cb = $('show-' + k); if (cb){ cb.disabled = !sets[k].children.length; cb.addEventListener('change', ()=>{ sets[k].visible = cb.checked; }); sets[k].visible = cb.checked; } }
// ------------------------------------------------------------------ colours
function colour(ind){
  const spec = IND.find(x=>x[0]===ind); const map = spec ? spec[2] : 'grey';
  const r = DATA.ranges[ind] || [0,1];
  for (const m of meshes){
    if (ind==='zebra' || ind==='isophote'){ zebraMat.uniforms.mode.value = ind==='zebra'?0:1; m.material = zebraMat; continue; }
    m.material = shadedMat;
    const col = m.geometry.getAttribute('color'); const v = m.userData.vals[ind];
    for (let i=0;i<col.count;i++){
      let c;
      if (ind==='shaded' || !v) c = [0.78,0.8,0.84];
      else if (!isFinite(v[i])) c = [1,0,1];
      else c = cmap(map, (v[i]-r[0])/((r[1]-r[0])||1));
      col.setXYZ(i, c[0], c[1], c[2]);
    }
    col.needsUpdate = true;
  }
  const title = ind==='draft' ? 'draft, deg (pull ' + $('pull').selectedOptions[0].text + ')' : (spec ? spec[1] : '');
  drawLegend(ind, map, r, title);
}
function drawLegend(ind, map, r, title){
  const box = $('legend'); const cv = box.querySelector('canvas'); const ctx = cv.getContext('2d');
  const show = !(ind==='zebra'||ind==='isophote'||ind==='shaded'); box.style.display = show?'block':'none'; if(!show) return;
  for (let y=0;y<cv.height;y++){ const c = cmap(map, 1-y/(cv.height-1)); ctx.fillStyle='rgb('+c.map(x=>Math.round(255*x)).join(',')+')'; ctx.fillRect(0,y,cv.width,1); }
  box.querySelector('.hi').textContent = r[1].toPrecision(3); box.querySelector('.lo').textContent = r[0].toPrecision(3);
  box.querySelector('.title').textContent = title;
}
// ------------------------------------------------------------------ camera
const dir = new THREE.Vector3(1,-1,0.8).normalize();
camera.up.set(0,0,1); camera.position.copy(sph.center.clone().add(dir.multiplyScalar(R*4.0))); camera.near=R/100; camera.far=R*100; camera.updateProjectionMatrix();
const controls = new THREE.OrbitControls(camera, canvas); controls.target.copy(sph.center); controls.update();
function resize(){ const w=canvas.clientWidth, h=canvas.clientHeight; renderer.setSize(w,h,false); camera.aspect=w/h; camera.updateProjectionMatrix(); }
// ------------------------------------------------------------------ picking and highlighting
const tint = new THREE.MeshBasicMaterial({color:0xff8c00, transparent:true, opacity:0.5, side:THREE.DoubleSide, depthWrite:false,
  polygonOffset:true, polygonOffsetFactor:-1, polygonOffsetUnits:-1});
let picked = null;
function highlight(index){
  if (picked){ scene.remove(picked); picked = null; }
  const m = byIndex[index]; if (m === undefined) return false;
  picked = new THREE.Mesh(m.geometry, tint); picked.renderOrder = 2; scene.add(picked); return true;
}
function pick(clientX, clientY){
  const b = canvas.getBoundingClientRect();
  const x = (clientX-b.left)/b.width*2-1, y = 1-(clientY-b.top)/b.height*2;
  const o = new THREE.Vector3(x,y,-1).unproject(camera), d = new THREE.Vector3(x,y,1).unproject(camera).sub(o).normalize();
  let best = Infinity, hit = null;
  for (const m of meshes){
    const s = m.geometry.boundingSphere, oc = s.center.clone().sub(o), tc = oc.dot(d);
    if (oc.lengthSq() - tc*tc > s.radius*s.radius) continue;
    const P = m.geometry.getAttribute('position').array, I = m.geometry.index.array;
    for (let t=0;t<I.length;t+=3){  // Moller-Trumbore
      const a=3*I[t], bb=3*I[t+1], c=3*I[t+2];
      const e1x=P[bb]-P[a], e1y=P[bb+1]-P[a+1], e1z=P[bb+2]-P[a+2], e2x=P[c]-P[a], e2y=P[c+1]-P[a+1], e2z=P[c+2]-P[a+2];
      const px=d.y*e2z-d.z*e2y, py=d.z*e2x-d.x*e2z, pz=d.x*e2y-d.y*e2x, det=e1x*px+e1y*py+e1z*pz;
      if (Math.abs(det) < 1e-30) continue;
      const inv=1/det, tx=o.x-P[a], ty=o.y-P[a+1], tz=o.z-P[a+2], u=(tx*px+ty*py+tz*pz)*inv;
      if (u<0 || u>1) continue;
      const qx=ty*e1z-tz*e1y, qy=tz*e1x-tx*e1z, qz=tx*e1y-ty*e1x, v=(d.x*qx+d.y*qy+d.z*qz)*inv;
      if (v<0 || u+v>1) continue;
      const dist=(e2x*qx+e2y*qy+e2z*qz)*inv;
      if (dist>0 && dist<best){ best=dist; hit=m; }
    }
  }
  return hit ? {index: hit.userData.index, point: o.clone().add(d.multiplyScalar(best))} : null;
}
function faceRow(index){ return rows('face-table').find(r => r.dataset.face === String(index)); }
function select(index, from){
  const ok = highlight(index);  // null clears
  markRow('face-table', ok ? faceRow(index) : null);
  pickOut.textContent = ok ? 'face ' + index + ' selected (' + from + '); its row is marked in the faces table.' : '';
}
let down = null;
canvas.addEventListener('pointerdown', e => { down = [e.clientX, e.clientY]; });
canvas.addEventListener('pointerup', e => {
  if (!down || Math.hypot(e.clientX-down[0], e.clientY-down[1]) > 4){ down = null; return; }
  down = null; const h = pick(e.clientX, e.clientY); select(h ? h.index : null, 'clicked in the view');
});
for (const r of rows('face-table')) r.addEventListener('click', () => select(Number(r.dataset.face), 'row clicked'));
// an edge row: fly to the edge's worst point and mark it
const mark = new THREE.Group(); mark.visible = false; mark.renderOrder = 3; scene.add(mark);
{ const s = R*0.02, v = new Float32Array([s,0,0, -s,0,0, 0,s,0, 0,-s,0, 0,0,s, 0,0,-s]);
  const g = new THREE.BufferGeometry(); g.setAttribute('position', new THREE.BufferAttribute(v, 3));
  g.setIndex([0,2,4, 2,1,4, 1,3,4, 3,0,4, 2,0,5, 1,2,5, 3,1,5, 0,3,5]);
  const m = new THREE.Mesh(g, new THREE.MeshBasicMaterial({color:0xe00000, depthTest:false, side:THREE.DoubleSide})); m.renderOrder = 3; mark.add(m);
  const x = lineSet(crosses(new Float32Array([0,0,0]), R*0.06), [0.9,0,0]); x.material.depthTest = false; x.renderOrder = 3; mark.add(x); }
let fly = null;
function flyTo(p){
  const to = new THREE.Vector3(p[0], p[1], p[2]);
  const off = camera.position.clone().sub(controls.target); const dist = Math.min(off.length(), R*1.6);
  fly = {t0: performance.now(), a: controls.target.clone(), b: to, ca: camera.position.clone(),
         cb: to.clone().add(off.normalize().multiplyScalar(dist))};
  mark.position.copy(to); mark.visible = true;
}
for (const r of rows('edge-table')) r.addEventListener('click', () => {
  if (!r.dataset.point) return;
  const p = r.dataset.point.split(',').map(Number); markRow('edge-table', r); flyTo(p);
  pickOut.textContent = 'edge ' + r.dataset.edge + ': worst point (' + p.map(x=>x.toPrecision(5)).join(', ') + ') marked red.';
});
// ------------------------------------------------------------------ controls
const sel = $('indicator'), pull = $('pull'), stripes = $('zebra-count'), sdir = $('zebra-dir'), iso = $('iso-count');
function num(el, lo, hi, dflt){ const v = parseFloat(el.value); return isFinite(v) ? Math.min(hi, Math.max(lo, v)) : dflt; }
sel.addEventListener('change', ()=>{ colour(sel.value); });
pull.addEventListener('change', ()=>{ setPull(pull.value.split(',').map(Number)); if (sel.value==='draft') colour('draft'); });
stripes.addEventListener('input', ()=>{ zebraMat.uniforms.pairs.value = num(stripes, 1, 64, 8); });
iso.addEventListener('input', ()=>{ zebraMat.uniforms.iso.value = num(iso, 1, 64, 6); });
sdir.addEventListener('change', ()=>{ const a = sdir.value.split(',').map(Number); zebraMat.uniforms.axis.value.set(a[0], a[1], a[2]).normalize(); });
resize(); setPull(pull.value.split(',').map(Number)); colour(sel.value);
// drawn on demand (after a control, a click, the orbit controls or a flight), not every frame:
// an idle report costs no GPU (or, under SwiftShader, CPU) time
let dirty = true; const redraw = () => { dirty = true; };
for (const ev of ['input','change','click']) document.addEventListener(ev, redraw);
controls.addEventListener('change', redraw);
function loop(now){
  if (fly){ const t = Math.min(1, Math.max(0, now - fly.t0)/500), e = t*t*(3-2*t);
    controls.target.lerpVectors(fly.a, fly.b, e); camera.position.lerpVectors(fly.ca, fly.cb, e); if (t >= 1) fly = null; dirty = true; }
  controls.update();
  if (dirty){ dirty = false; renderer.render(scene, camera); }
  requestAnimationFrame(loop); }
window.addEventListener('resize', () => { resize(); redraw(); }); requestAnimationFrame(loop);
// what the page decoded, for tests: a face's positions, normals, triangles or one indicator's values
function arrays(index, name){ const m = byIndex[index]; if (!m) return null; const g = m.geometry;
  const a = name==='triangles' ? g.index.array : name==='points' ? g.getAttribute('position').array :
            name==='normals' ? g.getAttribute('normal').array : m.userData.vals[name];
  return a ? Array.from(a) : null; }
window.occsurfViewer = {ready:true, meshes: meshes.length, pick, select, arrays, target: () => controls.target.toArray()};
if (!DATA.skipped) status.textContent = meshes.length + ' faces, ' + DATA.n_vertices + ' vertices: drag to rotate, wheel to zoom, right-drag to pan; click a face or a table row.';
document.body.setAttribute('data-viewer', 'ready');
})();
"""
