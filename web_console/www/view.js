// The live 3-D view: what the session's screens (graphics nodes) show, drawn with three.js
// (Debian's libjs-three, served by the console). World frame W is z-up, in metres.
// - the current world's objects (boxes, spheres, and meshes as glTF 2.0 the console exported
//   once, vertex k of a glTF being node id k of the Deformation topic), from each state (5/s);
// - the moving bodies (object states) and the controls in their states, drawn where the screens
//   draw them, from the bodies document (20/s at most);
// - the deformed meshes, from the deformation document (10/s at most);
// - every user's hand as the screens draw it (the figure the console computed with the screens'
//   rule: palm and fingers' links, a HIRO II's hand, a pen or gripper) and their fingertips,
//   from the hands document (20/s at most);
// - the message board in English or Japanese (the switch, or ?lang=ja).
// A graphics node's camera may be given in the URL, to see what its frames show:
//   ?eye=X,Y,Z&target=X,Y,Z&up=X,Y,Z&fov_y=RAD&size=WxH  (its camera.json; W and H in CSS px)
import * as THREE from "/three/build/three.module.js";
import {GLTFLoader} from "/three/examples/jsm/loaders/GLTFLoader.js";
import {OrbitControls} from "/three/examples/jsm/controls/OrbitControls.js";

const FINGER_RGB = [0xff0000, 0x00ff00, 0x0000ff, 0xffff00, 0x00ffff];  // thumb first, as the screens
// The draw order of the hands, as the screens': the scene, then the hands' boxes and spheres
// (hidden by the scene in front of them, writing no depth), then the fingertips, which so show
// through their hand.
const ORDER_HAND_BOX = 1, ORDER_HAND_SPHERE = 2, ORDER_FINGERTIP = 3;
const LANGUAGES = ["en", "ja"];
const status = document.getElementById("status");
const params = new URLSearchParams(location.search);
const view = {
  world: null, revision: -1, objects: 0, meshesLoaded: 0, meshesFailed: 0, hands: {}, palms: {}, figures: {}, frames: 0,
  // The senders' stamps of what is drawn: each hand's device state and each body's object state
  // (stamp_ns, decimal strings), each mesh's deformation revision: what a graphics node's
  // frame_times.csv says of its frames.
  stamps: {hands: {}, bodies: {}, deformations: {}},
  bodies: {}, controls: {}, deformations: {}, board: null,
  language: LANGUAGES.includes(params.get("lang")) ? params.get("lang") : "en",
};
window.handshareView = view;  // what the page shows, for tests and the curious

// The camera: the visitor's side (-y), above the table, unless the URL names one (checked: a
// bad parameter is said in the status line and the default kept).
const badParams = [];
function numbers(name, count, min, max) {
  const text = params.get(name);
  if (text === null) return null;
  const v = text.split(name === "size" ? "x" : ",").map(Number);
  if (v.length !== count || !v.every((x) => Number.isFinite(x) && x >= min && x <= max)) {
    badParams.push(name);
    return null;
  }
  return v;
}
const cameraSpec = {
  eye: numbers("eye", 3, -100, 100) || [0, -0.75, 0.55],
  target: numbers("target", 3, -100, 100) || [0, 0, 0.03],
  up: numbers("up", 3, -1, 1) || [0, 0, 1],
  fov_y_rad: (numbers("fov_y", 1, 0.01, 3.1) || [45 * Math.PI / 180])[0],
  size: numbers("size", 2, 16, 8192),  // null: the window's
};
view.camera = cameraSpec;
// preserveDrawingBuffer: the canvas can be read back (a test compares it with a graphics node's frame).
const renderer = new THREE.WebGLRenderer({antialias: true, canvas: document.getElementById("view"),
                                          preserveDrawingBuffer: true});
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20262e);
const camera = new THREE.PerspectiveCamera(cameraSpec.fov_y_rad * 180 / Math.PI, 1, 0.01, 50);
camera.up.set(...cameraSpec.up);
camera.position.set(...cameraSpec.eye);
camera.lookAt(...cameraSpec.target);
// A visitor turns the view with one finger (or the mouse), zooms and pans with two (or the
// wheel and the right button), about the table, never under it; a graphics node's camera in the
// URL stays fixed (a picture to compare with its frames). three.js' OrbitControls, from
// libjs-three like three.js itself.
let orbit = null;
if (params.get("eye") === null) {
  orbit = new OrbitControls(camera, renderer.domElement);
  orbit.target.set(...cameraSpec.target);
  orbit.minDistance = 0.15;
  orbit.maxDistance = 3.0;
  orbit.maxPolarAngle = 0.47 * Math.PI;  // from the table's up (+z): down to just above its plane
  orbit.update();
}
view.orbit = () => orbit ? {eye: camera.position.toArray(), target: orbit.target.toArray()} : null;
scene.add(new THREE.AmbientLight(0xffffff, 0.45));
const sun = new THREE.DirectionalLight(0xffffff, 0.8);
sun.position.set(0.5, -1, 2);
scene.add(sun);
let worldGroup = new THREE.Group();
scene.add(worldGroup);
const handGroup = new THREE.Group();
scene.add(handGroup);
const loader = new GLTFLoader();
const glbCache = new Map();  // URL -> promise of the loaded scene
let holders = new Map();     // object id -> its group in worldGroup (placed at X_WO)
let meshOf = new Map();      // object id -> its glTF mesh, once loaded
let lastBodies = null;       // the newest bodies and deformation documents: applied again to a
let lastDeformation = null;  // world rebuilt or a mesh loaded after them
let lastBoards = {};

function resize() {
  if (cameraSpec.size) {  // a graphics node's image: its pixels, one per CSS pixel
    renderer.setPixelRatio(1);
    renderer.setSize(cameraSpec.size[0], cameraSpec.size[1], true);
    camera.aspect = cameraSpec.size[0] / cameraSpec.size[1];
    camera.updateProjectionMatrix();
    return;
  }
  const w = window.innerWidth, h = window.innerHeight;
  renderer.setSize(w, h, false);
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener("resize", resize);
resize();

function colour(rgb) {
  return new THREE.Color(rgb[0], rgb[1], rgb[2]);
}

function setPose(node, p, q_wxyz) {
  node.position.set(p[0], p[1], p[2]);
  node.quaternion.set(q_wxyz[1], q_wxyz[2], q_wxyz[3], q_wxyz[0]);
}

// Where a node is drawn in W: [p_WO_m, q_WO_wxyz], read back from the three.js scene.
function poseOf(node) {
  node.updateMatrixWorld(true);
  const p = node.getWorldPosition(new THREE.Vector3());
  const q = node.getWorldQuaternion(new THREE.Quaternion());
  return [p.toArray(), [q.w, q.x, q.y, q.z]];
}

function loadGlb(url) {
  if (!glbCache.has(url)) {
    glbCache.set(url, new Promise((resolve, reject) => loader.load(url, (g) => resolve(g.scene), undefined, reject)));
  }
  return glbCache.get(url);
}

function buildWorld(w) {
  // The last world's GPU buffers go with it (the glTF meshes' geometry stays: cached and shared).
  worldGroup.traverse((n) => {
    if (!n.isMesh) return;
    if (n.material.map) n.material.map.dispose();
    n.material.dispose();
    if (!n.userData.shared) n.geometry.dispose();
  });
  scene.remove(worldGroup);
  worldGroup = new THREE.Group();
  scene.add(worldGroup);
  holders = new Map();
  meshOf = new Map();
  view.world = w.scene;
  view.revision = w.revision;
  view.objects = w.view.length;
  view.meshesLoaded = 0;
  view.meshesFailed = 0;
  view.bodies = {};
  view.controls = {};
  view.deformations = {};
  view.stamps.bodies = {};
  view.stamps.deformations = {};
  const group = worldGroup;
  for (const o of w.view) {
    const material = new THREE.MeshPhongMaterial({color: colour(o.rgb)});
    const holder = new THREE.Group();
    holder.name = o.id;
    holder.userData.rest = o;  // the scene state's pose: where it is drawn until a state moves it
    setPose(holder, o.p_WO_m, o.q_WO_wxyz);
    group.add(holder);
    holders.set(o.id, holder);
    if (o.shape === "box") {
      const h = o.half_extent_m;
      holder.add(new THREE.Mesh(new THREE.BoxBufferGeometry(2 * h[0], 2 * h[1], 2 * h[2]), material));
    } else if (o.shape === "sphere") {
      holder.add(new THREE.Mesh(new THREE.SphereBufferGeometry(o.half_extent_m[0], 32, 16), material));
    } else if (o.mesh) {
      loadGlb(o.mesh).then((loaded) => {
        if (group !== worldGroup) return;  // a newer world came meanwhile
        const copy = loaded.clone();
        copy.scale.set(o.mesh_scale[0], o.mesh_scale[1], o.mesh_scale[2]);
        copy.traverse((n) => {
          if (!n.isMesh) return;
          n.material = material;
          n.userData.shared = true;
          if (!meshOf.has(o.id)) meshOf.set(o.id, n);
        });
        holder.add(copy);
        view.meshesLoaded += 1;
        if (lastDeformation) showDeformation(lastDeformation);
      }, () => { view.meshesFailed += 1; });
    }
  }
  if (lastBodies) showBodies(lastBodies);
  if (lastDeformation) showDeformation(lastDeformation);
}

// A canvas texture with a book page's text, wrapped to the page (as the screens' caption).
function pageTexture(text) {
  const canvas = document.createElement("canvas");
  canvas.width = 256;
  canvas.height = 360;
  const g = canvas.getContext("2d");
  g.fillStyle = "#f5f0e1";
  g.fillRect(0, 0, canvas.width, canvas.height);
  g.fillStyle = "#222";
  g.font = "20px sans-serif";
  let line = "", y = 34;
  // Words for English, characters for Japanese (no spaces between its words).
  const pieces = /\s/.test(text) ? text.split(/(\s+)/) : Array.from(text);
  for (const piece of pieces) {
    if (g.measureText(line + piece).width > canvas.width - 24 && line.trim()) {
      g.fillText(line.trim(), 12, y);
      line = "";
      y += 26;
    }
    line += piece;
  }
  if (line.trim()) g.fillText(line.trim(), 12, y);
  const texture = new THREE.CanvasTexture(canvas);
  texture.minFilter = THREE.LinearFilter;  // no mipmaps: WebGL 1 would scale the canvas to a power of two
  return texture;
}

// An open book as the screens draw it (graphics_node's SceneReplica::AddBook): its front cover
// flat on the left, the spread's pages, the page's text on the right one; in its frame C (the
// closed book's top at z = 0, spine along y at x = -w/2).
function openBook(holder, c) {
  const [w, h, t] = c.size_m;
  const cover = Math.min(0.003, t / 5), inset = Math.min(0.003, w / 20);
  const spread = new THREE.Group();
  spread.name = "spread";
  const rgb = holder.userData.rest.rgb;
  const box = (lo, hi, material) => {
    const m = new THREE.Mesh(new THREE.BoxBufferGeometry(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]), material);
    m.position.set((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
    spread.add(m);
  };
  const paper = new THREE.MeshPhongMaterial({color: 0xf5f0e1});
  box([-1.5 * w, -0.5 * h, -t], [-0.5 * w, 0.5 * h, -t + cover], new THREE.MeshPhongMaterial({color: colour(rgb)}));
  box([-1.5 * w + inset, -0.5 * h + inset, -t + cover], [-0.5 * w, 0.5 * h - inset, 0], paper);
  const text = c.page_text[view.language] || "";
  const page = new THREE.Mesh(new THREE.PlaneBufferGeometry(w - 2 * inset, h - 2 * inset),
                              new THREE.MeshBasicMaterial({map: pageTexture(text)}));
  page.position.set(0, 0, 0.0004);  // the print lies on the paper
  spread.add(page);
  spread.userData.text = text;
  spread.userData.picture = null;
  if (c.page_picture) {
    // The picture on the left page, from -1.5 w + inset to -w/2 (as the screens' AddBook).
    const [pw, ph] = [w - inset, h - 2 * inset];
    const left = new THREE.Mesh(new THREE.PlaneBufferGeometry(pw, ph),
                                new THREE.MeshBasicMaterial({map: picturePage(c.page_picture, pw, ph, spread)}));
    left.name = "picture";
    left.position.set(-w + inset / 2, 0, 0.0004);
    spread.add(left);
    spread.userData.picture = {url: c.page_picture, loaded: false};
  }
  holder.add(spread);
  return spread;
}

// A left page with its picture, laid out as the screens' page texture (graphics_node's
// ComposePage for a page without text): paper, a margin of 1/16 of its width, the picture fitted
// into the rest, centred across, at the top margin; the page pw x ph [m].
function picturePage(url, pw, ph, spread) {
  const canvas = document.createElement("canvas");
  canvas.width = 256;
  canvas.height = Math.round(256 * Math.min(4, Math.max(0.25, ph / pw)));
  const g = canvas.getContext("2d");
  g.fillStyle = "#f5f0e1";
  g.fillRect(0, 0, canvas.width, canvas.height);
  const texture = new THREE.CanvasTexture(canvas);
  texture.minFilter = THREE.LinearFilter;
  const image = new Image();
  image.onload = () => {
    const margin = Math.max(2, Math.trunc(canvas.width / 16));
    const innerW = Math.max(1, canvas.width - 2 * margin), roomH = Math.max(1, canvas.height - 2 * margin);
    const scale = Math.min(innerW / image.naturalWidth, roomH / image.naturalHeight);
    const pw_px = Math.max(1, Math.round(image.naturalWidth * scale));
    const ph_px = Math.max(1, Math.round(image.naturalHeight * scale));
    g.drawImage(image, margin + Math.trunc((innerW - pw_px) / 2), margin, Math.min(pw_px, innerW), ph_px);
    texture.needsUpdate = true;
    if (spread.userData.picture) {
      Object.assign(spread.userData.picture, {loaded: true, width_px: image.naturalWidth, height_px: image.naturalHeight});
    }
  };
  image.src = url;
  return texture;
}

function showBodies(doc) {
  lastBodies = doc;
  if (doc.scene !== view.world) return;
  view.bodies = {};
  view.stamps.bodies = {};
  for (const b of doc.bodies) {
    const holder = holders.get(b.id);
    if (!holder) continue;
    setPose(holder, b.p_WO_m, b.q_WO_wxyz);
    const [p, q] = poseOf(holder);
    view.bodies[b.id] = {p_WO_m: p, q_WO_wxyz: q, owner: b.owner};
    view.stamps.bodies[b.id] = b.stamp_ns;
  }
  view.controls = {};
  for (const c of doc.controls) {
    const holder = holders.get(c.id);
    if (!holder) continue;
    setPose(holder, c.p_WO_m, c.q_WO_wxyz);
    // A book open at a page: its spread, made again when the page or the language changes.
    let spread = holder.getObjectByName("spread");
    const text = c.type === "book" && c.engaged ? (c.page_text[view.language] || "") : null;
    const picture = c.type === "book" && c.engaged ? (c.page_picture || null) : null;
    if (spread && (spread.userData.text !== text || (spread.userData.picture || {}).url !== (picture || undefined))) {
      holder.remove(spread);
      spread.traverse((n) => { if (n.isMesh) { n.geometry.dispose(); if (n.material.map) n.material.map.dispose(); n.material.dispose(); } });
      spread = null;
    }
    if (!spread && text !== null) spread = openBook(holder, c);
    const [p, q] = poseOf(holder);
    view.controls[c.id] = {type: c.type, index: c.index, engaged: c.engaged, moving: c.moving, position: c.position,
                           user: c.user, p_WO_m: p, q_WO_wxyz: q, page: spread ? spread.userData.text : null,
                           picture: spread ? spread.userData.picture : null};
  }
}

// Vertex v of a deformed mesh is drawn at p_WV = X_WO S p_MV' with p_MV' = p_MV + S^-1 R_WO^T u_W[v]
// (S: the scene's mesh scale), that is at X_WO S p_MV + u_W[v], where the screens draw it.
function deform(id, o) {
  const mesh = meshOf.get(id);
  const holder = holders.get(id);
  if (!mesh || !holder) return false;
  if (mesh.userData.shared) {  // this object's own copy of the positions from now on
    mesh.geometry = mesh.geometry.clone();
    mesh.userData.shared = false;
    mesh.userData.p_MV = Float32Array.from(mesh.geometry.attributes.position.array);
  }
  const positions = mesh.geometry.attributes.position;
  if (positions.count !== o.vertex_count) return false;  // not the mesh the console numbered
  const p0 = mesh.userData.p_MV;
  const a = positions.array;
  a.set(p0);
  const R_OW = new THREE.Quaternion().copy(holder.quaternion).inverse();
  const s = mesh.parent.scale;
  const u = new THREE.Vector3();
  for (let k = 0; k < o.ids.length; ++k) {
    const v = o.ids[k];
    u.set(o.u_um[3 * k] * 1e-6, o.u_um[3 * k + 1] * 1e-6, o.u_um[3 * k + 2] * 1e-6).applyQuaternion(R_OW);
    a[3 * v] += u.x / s.x;
    a[3 * v + 1] += u.y / s.y;
    a[3 * v + 2] += u.z / s.z;
  }
  positions.needsUpdate = true;
  mesh.geometry.computeVertexNormals();
  mesh.geometry.computeBoundingSphere();
  return true;
}

function showDeformation(doc) {
  lastDeformation = doc;
  if (doc.scene !== view.world) return;
  for (const o of doc.objects) {
    if (deform(o.id, o)) {
      view.deformations[o.id] = {revision: o.revision, vertices: o.vertex_count, displaced: o.ids.length};
      view.stamps.deformations[o.id] = o.revision;
    }
  }
}

// For tests: the drawn mesh of object `id`: its vertices as the glTF has them (frame M, scale
// 1) and where they are drawn in W, flat [x, y, z, ...] in vertex order; null before it loads.
view.meshVertices = (id) => {
  const mesh = meshOf.get(id);
  if (!mesh) return null;
  mesh.updateMatrixWorld(true);
  const positions = mesh.geometry.attributes.position;
  const p_MV = mesh.userData.p_MV || positions.array;
  const p_WV = [];
  const v = new THREE.Vector3();
  for (let k = 0; k < positions.count; ++k) {
    v.fromBufferAttribute(positions, k).applyMatrix4(mesh.matrixWorld);
    p_WV.push(v.x, v.y, v.z);
  }
  return {p_MV: Array.from(p_MV), p_WV: p_WV};
};

const tips = new Map();     // "user/finger" -> its sphere, kept from one hands document to the next
const figures = new Map();  // user -> {group, material, boxes: [mesh], spheres: [mesh]}
const unitBox = new THREE.BoxBufferGeometry(1, 1, 1);
const unitSphere = new THREE.SphereBufferGeometry(1, 16, 12);

// A user's hand figure as the console sent it (boxes [x, y, z, hx, hy, hz, qw, qx, qy, qz] and
// spheres [x, y, z, r] in W, one colour): its meshes are kept and moved, more made or extra
// ones hidden when the figure changes (a stylus has one box, a hand 16).
function showFigure(user, fig) {
  let f = figures.get(user);
  if (!f) {
    f = {group: new THREE.Group(), boxes: [], spheres: [],
         material: new THREE.MeshPhongMaterial({color: 0xffffff, depthWrite: false})};
    f.group.name = "figure/" + user;
    figures.set(user, f);
    handGroup.add(f.group);
  }
  f.material.color.setRGB(fig.rgb[0], fig.rgb[1], fig.rgb[2]);
  const place = (list, geometry, order, k) => {
    while (list.length <= k) {
      const m = new THREE.Mesh(geometry, f.material);
      m.renderOrder = order;
      list.push(m);
      f.group.add(m);
    }
    list[k].visible = true;
    return list[k];
  };
  fig.boxes.forEach((b, k) => {
    const m = place(f.boxes, unitBox, ORDER_HAND_BOX, k);
    m.position.set(b[0], b[1], b[2]);
    m.scale.set(2 * b[3], 2 * b[4], 2 * b[5]);
    m.quaternion.set(b[7], b[8], b[9], b[6]);
  });
  fig.spheres.forEach((b, k) => {
    const m = place(f.spheres, unitSphere, ORDER_HAND_SPHERE, k);
    m.position.set(b[0], b[1], b[2]);
    m.scale.setScalar(b[3]);
  });
  for (let k = fig.boxes.length; k < f.boxes.length; ++k) f.boxes[k].visible = false;
  for (let k = fig.spheres.length; k < f.spheres.length; ++k) f.spheres[k].visible = false;
  // What is drawn, read back from the three.js scene: each box's centre, orientation and size,
  // each sphere's centre and radius, in W.
  f.group.updateMatrixWorld(true);
  const drawn = {rgb: f.material.color.toArray(), boxes: [], spheres: []};
  for (const m of f.boxes.slice(0, fig.boxes.length)) {
    const [p, q] = poseOf(m);
    drawn.boxes.push({p_W_m: p, q_WB_wxyz: q, size_m: m.getWorldScale(new THREE.Vector3()).toArray()});
  }
  for (const m of f.spheres.slice(0, fig.spheres.length)) {
    drawn.spheres.push({p_W_m: m.getWorldPosition(new THREE.Vector3()).toArray(), radius_m: m.scale.x});
  }
  return drawn;
}

function showHands(hands) {
  // Meshes are made once per fingertip and figure part and moved after: 20 documents a second
  // allocate nothing on the GPU; what is gone (its user left) is removed and freed.
  const seen = new Set();
  view.hands = {};
  view.palms = {};
  view.figures = {};
  view.stamps.hands = {};
  for (const h of hands) {
    view.hands[h.user] = [];  // where the spheres are drawn, in W
    view.stamps.hands[h.user] = h.stamp_ns;
    h.p_WE_m.forEach((p, k) => {
      const name = h.user + "/" + h.fingers[k];
      let tip = tips.get(name);
      if (!tip) {
        tip = new THREE.Mesh(new THREE.SphereBufferGeometry(1, 16, 12),
                             new THREE.MeshPhongMaterial({color: FINGER_RGB[h.fingers[k]]}));
        tip.name = name;
        tip.renderOrder = ORDER_FINGERTIP;
        tips.set(name, tip);
        handGroup.add(tip);
      }
      tip.scale.setScalar(h.radius_m);
      tip.position.set(p[0], p[1], p[2]);
      seen.add(name);
      view.hands[h.user].push(tip.getWorldPosition(new THREE.Vector3()).toArray());
    });
    if (h.figure) {
      const drawn = showFigure(h.user, h.figure);
      view.figures[h.user] = drawn;
      // A hand's first box is its palm (a pen or gripper has none: fewer than five fingers).
      if (h.fingers.length === FINGER_RGB.length && drawn.boxes.length) {
        view.palms[h.user] = {p_W_m: drawn.boxes[0].p_W_m, q_WB_wxyz: drawn.boxes[0].q_WB_wxyz};
      }
      seen.add("figure/" + h.user);
    }
  }
  for (const [name, tip] of tips) {
    if (seen.has(name)) continue;
    handGroup.remove(tip);
    tip.geometry.dispose();
    tip.material.dispose();
    tips.delete(name);
  }
  for (const [user, f] of figures) {
    if (seen.has("figure/" + user)) continue;
    handGroup.remove(f.group);
    f.material.dispose();  // the unit geometries are shared
    figures.delete(user);
  }
}

// For tests: the canvas drawn now (as PNG data URLs), and with `bare` drawn again without the
// hands, and the senders' stamps of what it shows (a graphics node's frame with the same stamps
// shows the same moment), and where the fingertips are drawn.
view.snapshot = (bare = true) => {
  const canvas = renderer.domElement;
  const shot = {stamps: JSON.parse(JSON.stringify(view.stamps)), hands: JSON.parse(JSON.stringify(view.hands))};
  renderer.render(scene, camera);
  shot.png = canvas.toDataURL("image/png");
  if (bare) {
    handGroup.visible = false;
    renderer.render(scene, camera);
    shot.bare = canvas.toDataURL("image/png");
    handGroup.visible = true;
    renderer.render(scene, camera);
  }
  return shot;
};

// The message board in the view's language (the screens show one language each; the page
// switches), as text only.
const boardText = document.getElementById("board-text");
const boardNext = document.getElementById("board-next");
function showBoard() {
  const b = lastBoards[view.language];
  document.getElementById("board").lang = view.language;
  boardText.textContent = b ? b.text : "";
  boardNext.textContent = b ? b.next_action : "";
  for (const button of document.querySelectorAll("#languages button")) {
    button.setAttribute("aria-pressed", String(button.dataset.lang === view.language));
  }
  view.board = b ? {language: view.language, message_id: b.message_id, text: boardText.textContent,
                    next_action: boardNext.textContent} : null;
}
for (const button of document.querySelectorAll("#languages button")) {
  button.addEventListener("click", () => {
    view.language = button.dataset.lang;
    showBoard();
    if (lastBodies) showBodies(lastBodies);  // an open book's page in the new language
  });
}
showBoard();

function badNote() {
  return badParams.length ? " (bad URL parameters, not used: " + badParams.join(", ") + ")" : "";
}

function connect() {
  const socket = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  socket.onopen = () => { status.textContent = "live" + badNote(); };
  socket.onmessage = (event) => {
    const doc = JSON.parse(event.data);
    if (doc.type === "hands") {
      showHands(doc.hands);
    } else if (doc.type === "bodies") {
      showBodies(doc);
    } else if (doc.type === "deformation") {
      showDeformation(doc);
    } else if (doc.type === "state") {
      if (doc.world && (doc.world.scene !== view.world || doc.world.revision !== view.revision)) {
        buildWorld(doc.world);
        status.textContent = "live: " + doc.world.scene + badNote();
      }
      lastBoards = doc.boards || {};
      showBoard();
    }
  };
  socket.onclose = () => {
    status.textContent = "disconnected, reconnecting";
    setTimeout(connect, 2000);
  };
}

function frame() {
  renderer.render(scene, camera);
  view.frames += 1;
  requestAnimationFrame(frame);
}
connect();
requestAnimationFrame(frame);
