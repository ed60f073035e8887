// The live 3-D view: the current world's objects (boxes, spheres, and meshes as glTF 2.0 that
// the console exported once with assimp) and every user's fingertips as spheres, drawn with
// three.js (Debian's libjs-three, served by the console). World frame W is z-up, in metres.
// The console pushes the world with every state and the hands up to 20 times a second.
import * as THREE from "/three/build/three.module.js";
import {GLTFLoader} from "/three/examples/jsm/loaders/GLTFLoader.js";

const FINGER_RGB = [0xff0000, 0x00ff00, 0x0000ff, 0xffff00, 0x00ffff];  // thumb first, as the screens
const status = document.getElementById("status");
const view = {world: null, revision: -1, objects: 0, meshesLoaded: 0, meshesFailed: 0, hands: {}, frames: 0};
window.handshareView = view;  // what the page shows, for tests and the curious

const renderer = new THREE.WebGLRenderer({antialias: true, canvas: document.getElementById("view")});
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20262e);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 50);
camera.up.set(0, 0, 1);
camera.position.set(0, -0.75, 0.55);  // the visitor's side (-y), above the table
camera.lookAt(0, 0, 0.03);
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

function resize() {
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

function place(node, o) {
  node.position.set(o.p_WO_m[0], o.p_WO_m[1], o.p_WO_m[2]);
  node.quaternion.set(o.q_WO_wxyz[1], o.q_WO_wxyz[2], o.q_WO_wxyz[3], o.q_WO_wxyz[0]);
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
    n.material.dispose();
    if (!n.userData.shared) n.geometry.dispose();
  });
  scene.remove(worldGroup);
  worldGroup = new THREE.Group();
  scene.add(worldGroup);
  view.world = w.scene;
  view.revision = w.revision;
  view.objects = w.view.length;
  view.meshesLoaded = 0;
  view.meshesFailed = 0;
  const group = worldGroup;
  for (const o of w.view) {
    const material = new THREE.MeshPhongMaterial({color: colour(o.rgb)});
    const holder = new THREE.Group();
    holder.name = o.id;
    place(holder, o);
    group.add(holder);
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
        });
        holder.add(copy);
        view.meshesLoaded += 1;
      }, () => { view.meshesFailed += 1; });
    }
  }
}

const tips = new Map();  // "user/finger" -> its sphere, kept from one hands document to the next

function showHands(hands) {
  // Spheres are made once per fingertip and moved after: 20 documents a second allocate nothing
  // on the GPU; a fingertip that is gone (its user left) is removed and freed.
  const seen = new Set();
  view.hands = {};
  for (const h of hands) {
    view.hands[h.user] = [];  // where the spheres are drawn, in W
    h.p_WE_m.forEach((p, k) => {
      const name = h.user + "/" + h.fingers[k];
      let tip = tips.get(name);
      if (!tip) {
        tip = new THREE.Mesh(new THREE.SphereBufferGeometry(1, 16, 12),
                             new THREE.MeshPhongMaterial({color: FINGER_RGB[h.fingers[k]]}));
        tip.name = name;
        tips.set(name, tip);
        handGroup.add(tip);
      }
      tip.scale.setScalar(h.radius_m);
      tip.position.set(p[0], p[1], p[2]);
      seen.add(name);
      view.hands[h.user].push(tip.getWorldPosition(new THREE.Vector3()).toArray());
    });
  }
  for (const [name, tip] of tips) {
    if (seen.has(name)) continue;
    handGroup.remove(tip);
    tip.geometry.dispose();
    tip.material.dispose();
    tips.delete(name);
  }
}

function connect() {
  const socket = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  socket.onopen = () => { status.textContent = "live"; };
  socket.onmessage = (event) => {
    const doc = JSON.parse(event.data);
    if (doc.type === "hands") {
      showHands(doc.hands);
    } else if (doc.type === "state" && doc.world && (doc.world.scene !== view.world || doc.world.revision !== view.revision)) {
      buildWorld(doc.world);
      status.textContent = "live: " + doc.world.scene;
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
