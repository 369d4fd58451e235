// The moslam viewer page: reads the server's messages (message.h describes their layout), draws
// the map with three.js (Debian's libjs-three, served by moslam), and sends pause / step /
// resume and the toggles of what is sent only on demand (the keyframe graph, the depth image).
// Its state is kept in window.moslam, which the browser test (browser_test.cc) reads.
'use strict';

const POINT_COLOURS = [  // slam::ViewPointState
  ['in the map', 0xb0b0b0], ['local map', 0x3399ff], ['tracked now', 0x33dd55],
  ['new', 0xffcc00], ['erased: movable', 0xff3344], ['erased: other', 0x885588]];
const KEYPOINT_COLOURS = [  // slam::ViewKeypointKind
  ['untracked', '#ffd24d'], ['tracked', '#33dd55'], ['near the mask', '#ff3344'],
  ['seen moving', '#33e0ff']];
const REJECTED_COLOUR = '#ff66ff';  // keypoints the movable mask took away (drawn as crosses)
const GRAPH_COLOURS = {covisibility: 0x00c8c8, spanning_tree: 0xffffff, loop: 0xff33ff};
const ERASED_FIRST = 4;
const NOTICE_MS = 6000;  // how long a closed loop's notice stays

const state = window.moslam = {
  connected: false, messages: 0, paused: false, finished: false, replay: false,
  // Status messages (pause state, toggles) received: one per command the server has carried out.
  statuses: 0,
  frame: -1, frames: 0, keyframes: 0, mapPoints: 0, erasedPoints: 0, keypoints: 0,
  trajectory: 0, groundTruth: 0, webgl: true, numbers: {}, error: '',
  // Sent on demand: what the last message held, and how many messages held it.
  graphOn: false, covisibilityEdges: 0, spanningEdges: 0, graphMessages: 0,
  depthOn: false, depthMessages: 0, depthWidth: 0,
  // Always sent: keypoints the mask took away (the last frame's, the most seen) and closed loops.
  rejectedKeypoints: 0, rejectedMax: 0, loops: 0, loopNotices: 0, notice: '', viewMessages: 0,
};

let socket = null;
let lastMessage = null;  // kept out of window.moslam, which stays small to read
function send(cmd, extra) {
  if (socket && socket.readyState === WebSocket.OPEN) {
    socket.send(JSON.stringify(Object.assign({cmd: cmd}, extra || {})));
  }
}
window.moslamCommand = send;

// --- 3D scene ---------------------------------------------------------------------------------
const container = document.getElementById('scene');
let renderer = null, scene = null, camera = null, controls = null, world = null;
const objects = {};
try {
  renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  container.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  scene.background = new THREE.Color(0x111111);
  camera = new THREE.PerspectiveCamera(60, window.innerWidth / window.innerHeight, 0.01, 5000);
  camera.position.set(0, 1.5, 3);  // behind and above the first camera (scene: y up, -z ahead)
  controls = new THREE.OrbitControls(camera, renderer.domElement);
  // Camera frames have y down and z forward; turned about x, the first camera's up is up.
  world = new THREE.Group();
  world.rotation.x = Math.PI;
  scene.add(world);
  world.add(new THREE.AxesHelper(0.3));
} catch (e) {
  state.webgl = false;
  state.error = 'no WebGL: ' + e;
  document.getElementById('banner').textContent = state.error;
}

function replace(name, object) {
  if (objects[name]) {
    world.remove(objects[name]);
    objects[name].geometry.dispose();
    objects[name].material.dispose();
  }
  objects[name] = object;
  if (object) world.add(object);
}

function lineObject(positions, colour, segments) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  const material = new THREE.LineBasicMaterial({color: colour});
  return segments ? new THREE.LineSegments(geometry, material) : new THREE.Line(geometry, material);
}

// Frustum lines of each 3x4 pose (R row-major, then t): centre to 4 corners, and the rectangle.
function frustums(poses, size, aspect) {
  const n = poses.length / 12;
  const w = size * aspect * 0.5, h = size * 0.5, d = size;
  const corners = [[-w, -h, d], [w, -h, d], [w, h, d], [-w, h, d]];
  const out = new Float32Array(n * 16 * 3);
  let k = 0;
  const put = (p, c) => {
    for (let r = 0; r < 3; ++r) {
      out[k++] = p[r * 3] * c[0] + p[r * 3 + 1] * c[1] + p[r * 3 + 2] * c[2] + p[9 + r];
    }
  };
  for (let i = 0; i < n; ++i) {
    const p = poses.subarray(i * 12, i * 12 + 12);
    for (let c = 0; c < 4; ++c) { put(p, [0, 0, 0]); put(p, corners[c]); }
    for (let c = 0; c < 4; ++c) { put(p, corners[c]); put(p, corners[(c + 1) % 4]); }
  }
  return out;
}

function drawScene(m, s) {
  if (!renderer) return;
  const aspect = (m.header.image_width || 4) / (m.header.image_height || 3);
  if (s.points) {
    const states = s.point_states;
    const showErased = document.getElementById('erased').checked;
    const keep = [];
    for (let i = 0; i < states.length; ++i) if (showErased || states[i] < ERASED_FIRST) keep.push(i);
    const positions = new Float32Array(keep.length * 3), colours = new Float32Array(keep.length * 3);
    const colour = new THREE.Color();
    keep.forEach((i, j) => {
      positions.set(s.points.subarray(i * 3, i * 3 + 3), j * 3);
      colour.setHex(POINT_COLOURS[states[i]] ? POINT_COLOURS[states[i]][1] : 0xffffff);
      colours[j * 3] = colour.r; colours[j * 3 + 1] = colour.g; colours[j * 3 + 2] = colour.b;
    });
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    replace('points', new THREE.Points(geometry, new THREE.PointsMaterial(
        {size: 3, sizeAttenuation: false, vertexColors: THREE.VertexColors})));
  }
  if (s.keyframes) {
    replace('keyframes', lineObject(frustums(s.keyframes, 0.08, aspect), 0x4477ff, true));
    drawGraph(s, aspect);
  }
  if (s.trajectory && s.trajectory.length >= 6) replace('trajectory', lineObject(s.trajectory.slice(), 0x33dd55));
  const gt = s.ground_truth && s.ground_truth.length >= 6 && document.getElementById('gt').checked;
  replace('gt', gt ? lineObject(s.ground_truth.slice(), 0xff9933) : null);
  if (s.camera) {
    replace('camera', lineObject(frustums(s.camera, 0.15, aspect), 0xff2222, true));
    if (document.getElementById('follow').checked) follow(s.camera);
  }
}

// Line segments between keyframe centres; `pairs` is a Uint32Array of `stride` numbers per edge,
// the two keyframe indices first.
function edgeLines(poses, pairs, stride, colour) {
  const n = Math.floor(pairs.length / stride), out = new Float32Array(n * 6);
  for (let e = 0; e < n; ++e) {
    for (let end = 0; end < 2; ++end) {
      const k = pairs[e * stride + end] * 12;
      out.set(poses.subarray(k + 9, k + 12), e * 6 + end * 3);
    }
  }
  return lineObject(out, colour, true);
}

// The keyframe graph when the page shows it, and the closed loops always: their edge and their
// two keyframes in the loop colour.
function drawGraph(s, aspect) {
  const show = document.getElementById('graph').checked;
  replace('covisibility', show && s.covisibility && s.covisibility.length ?
      edgeLines(s.keyframes, s.covisibility, 3, GRAPH_COLOURS.covisibility) : null);
  replace('spanning_tree', show && s.spanning_tree && s.spanning_tree.length ?
      edgeLines(s.keyframes, s.spanning_tree, 2, GRAPH_COLOURS.spanning_tree) : null);
  if (!s.loops || !s.loops.length) { replace('loops', null); replace('loop_keyframes', null); return; }
  replace('loops', edgeLines(s.keyframes, s.loops, 2, GRAPH_COLOURS.loop));
  const poses = new Float32Array(s.loops.length * 12);
  s.loops.forEach((k, j) => poses.set(s.keyframes.subarray(k * 12, k * 12 + 12), j * 12));
  replace('loop_keyframes', lineObject(frustums(poses, 0.12, aspect), GRAPH_COLOURS.loop, true));
}

// Keeps the orbit's offset and moves its target onto the current camera.
function follow(pose) {
  const target = new THREE.Vector3(pose[9], pose[10], pose[11]).applyMatrix4(world.matrixWorld);
  const offset = camera.position.clone().sub(controls.target);
  controls.target.copy(target);
  camera.position.copy(target).add(offset);
}

function animate() {
  requestAnimationFrame(animate);
  if (renderer) { controls.update(); renderer.render(scene, camera); }
}
if (renderer) {
  world.updateMatrixWorld();
  animate();
  window.addEventListener('resize', () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
  });
}

// --- the current image --------------------------------------------------------------------------
const imageCanvas = document.getElementById('image');
async function drawImage(m, s, buffer) {
  if (!s.image) return;
  const image = await createImageBitmap(new Blob([s.image], {type: 'image/jpeg'}));
  imageCanvas.width = image.width; imageCanvas.height = image.height;
  const g = imageCanvas.getContext('2d');
  g.drawImage(image, 0, 0);
  if (s.mask) {
    const mask = await createImageBitmap(new Blob([s.mask], {type: 'image/png'}));
    const tmp = document.createElement('canvas');
    tmp.width = image.width; tmp.height = image.height;
    const t = tmp.getContext('2d');
    t.drawImage(mask, 0, 0, image.width, image.height);
    const pixels = t.getImageData(0, 0, tmp.width, tmp.height);
    let covered = 0;
    for (let i = 0; i < pixels.data.length; i += 4) {
      const on = pixels.data[i] > 127;
      covered += on ? 1 : 0;
      pixels.data[i] = 255; pixels.data[i + 1] = 40; pixels.data[i + 2] = 60;
      pixels.data[i + 3] = on ? 110 : 0;
    }
    t.putImageData(pixels, 0, 0);
    g.drawImage(tmp, 0, 0);
    state.maskPixels = covered;
  }
  const scale = m.header.image_scale || 1;
  if (s.keypoints) {
    for (let i = 0; i < s.keypoint_kinds.length; ++i) {
      g.strokeStyle = KEYPOINT_COLOURS[s.keypoint_kinds[i]][1];
      g.strokeRect(s.keypoints[2 * i] * scale - 2, s.keypoints[2 * i + 1] * scale - 2, 4, 4);
    }
  }
  if (s.rejected_keypoints) {
    g.strokeStyle = REJECTED_COLOUR;
    g.beginPath();
    for (let i = 0; i + 1 < s.rejected_keypoints.length; i += 2) {
      const x = s.rejected_keypoints[i] * scale, y = s.rejected_keypoints[i + 1] * scale;
      g.moveTo(x - 3, y - 3); g.lineTo(x + 3, y + 3);
      g.moveTo(x - 3, y + 3); g.lineTo(x + 3, y - 3);
    }
    g.stroke();
  }
}

// The depth image (a colour-mapped JPEG the server made), under the image while the page asks.
const depthCanvas = document.getElementById('depthimage');
async function drawDepth(m, s) {
  const box = document.getElementById('depthbox');
  if (!s.depth || !document.getElementById('depth').checked) { box.style.display = 'none'; return; }
  const image = await createImageBitmap(new Blob([s.depth], {type: 'image/jpeg'}));
  depthCanvas.width = image.width; depthCanvas.height = image.height;
  depthCanvas.getContext('2d').drawImage(image, 0, 0);
  box.style.display = 'block';
  document.getElementById('depthscale').textContent =
      'depth: blue 0 m ... red ' + fmt(m.header.depth_far_m, 2) + ' m, black: none';
  state.depthWidth = image.width;
}

// --- numbers -----------------------------------------------------------------------------------
function fmt(x, digits) { return typeof x === 'number' ? x.toFixed(digits) : (x === undefined ? '-' : x); }
function drawNumbers(h) {
  const ms = h.ms || {};
  const rows = [
    ['frame', h.frame === undefined ? '-' : h.frame], ['state', h.finished ? (h.replay ? 'finished run' : 'run ended: ' + h.state) : h.state],
    ['frames', h.frames], ['frames/s', fmt(h.fps, 1)],
    ['ms: mask / extract / track', [fmt(ms.mask, 1), fmt(ms.extract, 1), fmt(ms.track, 1)].join(' / ')],
    ['ms: local map / keyframe / total', [fmt(ms.local_map, 1), fmt(ms.keyframe, 1), fmt(ms.total, 1)].join(' / ')],
    ['keyframes', h.keyframes], ['map points', h.map_points],
    ['features / inliers', (h.features === undefined ? '-' : h.features) + ' / ' + (h.inliers === undefined ? '-' : h.inliers)],
    ['mask coverage', h.mask_coverage === undefined ? '-' : (100 * h.mask_coverage).toFixed(1) + ' %'],
    ['keypoints taken by the mask', state.rejectedKeypoints], ['loops closed', state.loops],
    ['paused', state.paused ? 'yes' : 'no']];
  document.getElementById('numbers').innerHTML =
      rows.map(r => '<tr><td>' + r[0] + '</td><td>' + r[1] + '</td></tr>').join('');
}

function drawLegend() {
  const sw = c => '<span class="sw" style="background:' + c + '"></span>';
  const hex = c => '#' + c.toString(16).padStart(6, '0');
  document.getElementById('legend').innerHTML =
      POINT_COLOURS.map(p => sw(hex(p[1])) + p[0]).join('<br>') + '<br>' +
      sw('#4477ff') + 'keyframes ' + sw('#ff2222') + 'camera<br>' + sw('#33dd55') +
      'trajectory ' + sw('#ff9933') + 'ground truth<br>' +
      sw(hex(GRAPH_COLOURS.covisibility)) + 'covisibility ' + sw(hex(GRAPH_COLOURS.spanning_tree)) +
      'spanning tree ' + sw(hex(GRAPH_COLOURS.loop)) + 'loop<br>keypoints: ' +
      KEYPOINT_COLOURS.map(k => sw(k[1]) + k[0]).join(' ') + ' ' + sw(REJECTED_COLOUR) +
      'taken by the mask';
}

// --- messages ----------------------------------------------------------------------------------
function decode(buffer) {
  const view = new DataView(buffer);
  const magic = String.fromCharCode(view.getUint8(0), view.getUint8(1), view.getUint8(2), view.getUint8(3));
  if (magic !== 'MSV1') throw new Error('not a viewer message');
  const n = view.getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 8, n)));
  const sections = {};
  let at = (8 + n + 3) & ~3;
  const types = {points: Float32Array, keyframes: Float32Array, keypoints: Float32Array,
                 trajectory: Float32Array, ground_truth: Float32Array, camera: Float32Array,
                 rejected_keypoints: Float32Array, point_states: Uint8Array,
                 keypoint_kinds: Uint8Array, loops: Uint32Array, covisibility: Uint32Array,
                 spanning_tree: Uint32Array};
  for (const s of header.sections) {
    const Type = types[s.name] || Uint8Array;
    sections[s.name] = new Type(buffer, at, s.bytes / Type.BYTES_PER_ELEMENT);
    at = (at + s.bytes + 3) & ~3;
  }
  return {header: header, sections: sections};
}

function onFrame(buffer) {
  const m = decode(buffer), h = m.header, s = m.sections;
  state.messages += 1;
  state.numbers = h;
  state.frame = h.frame === undefined ? state.frame : h.frame;
  state.frames = h.frames;
  state.finished = !!h.finished;
  state.replay = !!h.replay;
  if (s.keyframes) state.keyframes = s.keyframes.length / 12;
  if (s.point_states) {
    let erased = 0;
    for (const v of s.point_states) erased += v >= ERASED_FIRST ? 1 : 0;
    state.erasedPoints = erased;
    state.mapPoints = s.point_states.length - erased;
  }
  if (s.keypoint_kinds) state.keypoints = s.keypoint_kinds.length;
  if (s.keyframes) countOnDemand(h, s);
  state.trajectory = s.trajectory ? s.trajectory.length / 3 : 0;
  state.groundTruth = s.ground_truth ? s.ground_truth.length / 3 : 0;
  drawNumbers(h);
  drawScene(m, s);
  drawImage(m, s, buffer).catch(e => { state.error = 'image: ' + e; });
  drawDepth(m, s).catch(e => { state.error = 'depth: ' + e; });
  lastMessage = m;
}

// What the message held beyond the default, and a notice for each newly closed loop.
function countOnDemand(h, s) {
  state.rejectedKeypoints = s.rejected_keypoints ? s.rejected_keypoints.length / 2 : 0;
  state.rejectedMax = Math.max(state.rejectedMax, state.rejectedKeypoints);
  const hasGraph = !!(s.covisibility && s.spanning_tree);
  state.covisibilityEdges = hasGraph ? s.covisibility.length / 3 : 0;
  state.spanningEdges = hasGraph ? s.spanning_tree.length / 2 : 0;
  if (hasGraph) state.graphMessages += 1;
  if (s.depth) state.depthMessages += 1;
  const loops = s.loops ? s.loops.length / 2 : 0;
  // A page that connects after a loop learns of it without a notice.
  if (loops > state.loops && state.viewMessages > 0) {
    const k = 2 * (loops - 1);  // the newest loop is last
    showNotice('loop closed' + (h.frame === undefined ? '' : ' at frame ' + h.frame) +
               ': keyframe ' + s.loops[k + 1] + ' meets keyframe ' + s.loops[k]);
    state.loopNotices += loops - state.loops;  // loops announced (several may come at once)
  }
  state.loops = loops;
  state.viewMessages += 1;
}

let noticeTimer = null;
function showNotice(text) {
  const notice = document.getElementById('notice');
  notice.textContent = state.notice = text;
  notice.style.display = 'block';
  clearTimeout(noticeTimer);
  noticeTimer = setTimeout(() => { notice.style.display = 'none'; }, NOTICE_MS);
}

function connect() {
  socket = new WebSocket('ws://' + location.host + '/');
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { state.connected = true; document.getElementById('banner').textContent = ''; };
  socket.onclose = () => {
    state.connected = false;
    document.getElementById('banner').textContent = state.finished ? 'moslam has stopped' : 'reconnecting...';
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') {
      const status = JSON.parse(event.data);
      if (status.type === 'status') {
        state.statuses += 1;
        state.paused = status.paused;
        // The toggles hold for every browser: another page may have changed them.
        state.graphOn = document.getElementById('graph').checked = !!status.graph;
        state.depthOn = document.getElementById('depth').checked = !!status.depth;
        drawNumbers(state.numbers);
        if (lastMessage) drawScene(lastMessage, lastMessage.sections);
      }
      return;
    }
    try { onFrame(event.data); } catch (e) { state.error = String(e); }
    // Drawn: the server sends the next picture only while fewer than two are undrawn, so a page
    // slower than the run shows the latest frame rather than falling behind (server.h).
    send('ack');
  };
}

document.getElementById('pause').onclick = () => send('pause');
document.getElementById('step').onclick = () => send('step');
document.getElementById('resume').onclick = () => send('resume');
document.getElementById('shot').onclick = () => {
  if (!renderer) return;
  const a = document.createElement('a');
  a.href = renderer.domElement.toDataURL('image/png');
  a.download = 'moslam_frame_' + state.frame + '.png';
  a.click();
};
document.getElementById('erased').onchange = document.getElementById('gt').onchange = () => {
  if (lastMessage) drawScene(lastMessage, lastMessage.sections);
};
for (const name of ['graph', 'depth']) {
  document.getElementById(name).onchange = (e) => {
    send(name, {on: e.target.checked});
    if (lastMessage) drawScene(lastMessage, lastMessage.sections);
  };
}
window.addEventListener('keydown', (e) => {
  if (e.key === ' ') send(state.paused ? 'resume' : 'pause');
  if (e.key === 'n') send('step');
});
drawLegend();
drawNumbers({});
connect();
