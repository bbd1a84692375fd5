// The robot and the person in 3-D (three.js), drawn from the server's step messages.
import * as THREE from "/static/vendor/three.module.min.js";
import { $, BLUE, RED, dash } from "./dash.js";

// Robot frame: x forward (towards the person), y to the robot's left, z up (metres).
// three.js: X = y, Y = z, Z = x (a rotation), so the camera in front looks at the robot.
const v3 = (p) => new THREE.Vector3(p[1], p[2], p[0]);

export const robotView = (() => {
  const container = $("view3d");
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 1.5));
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color("#e9edf2");
  const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 20);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 2, 2);
  scene.add(sun);

  const shell = new THREE.MeshStandardMaterial({ color: 0xdfe3ea, roughness: 0.5 });
  const dark = new THREE.MeshStandardMaterial({ color: 0x3b4350, roughness: 0.6 });
  const joint = new THREE.MeshStandardMaterial({ color: 0x8792a5, roughness: 0.4 });
  const grid = new THREE.GridHelper(2.4, 24, 0xb6bdc8, 0xd3d8df);
  grid.position.z = 0.5;  // the floor between the robot and the person
  scene.add(grid);

  const add = (geometry, material, position) => {
    const mesh = new THREE.Mesh(geometry, material);
    if (position) mesh.position.copy(v3(position));
    scene.add(mesh);
    return mesh;
  };
  // Body from humanoid.xml (boxes: half sizes; three.js boxes take full sizes in X=y, Y=z, Z=x).
  add(new THREE.BoxGeometry(0.15, 0.18, 0.10), shell, [0, 0, 0.33]);            // chest
  add(new THREE.BoxGeometry(0.15, 0.06, 0.09), dark, [0, 0, 0.215]);            // pelvis
  for (const y of [0.045, -0.045]) {
    add(new THREE.CylinderGeometry(0.032, 0.032, 0.16, 16), shell, [0, y, 0.11]); // legs
    add(new THREE.BoxGeometry(0.07, 0.024, 0.12), dark, [0.02, y, 0.012]);      // feet
  }
  add(new THREE.CylinderGeometry(0.015, 0.015, 0.05, 12), dark, [-0.01, 0, 0.445]); // neck
  add(new THREE.SphereGeometry(0.05, 24, 16), shell, [-0.025, 0, 0.52]);        // head
  add(new THREE.BoxGeometry(0.07, 0.036, 0.012), dark, [0.016, 0, 0.52]);       // visor

  const limb = (radius, material = shell) => {
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 16), material);
    scene.add(mesh);
    return mesh;
  };
  const arms = [0, 1].map(() => ({
    shoulder: add(new THREE.SphereGeometry(0.028, 16, 12), joint),
    elbow: add(new THREE.SphereGeometry(0.02, 16, 12), joint),
    hand: add(new THREE.SphereGeometry(0.024, 16, 12), dark),
    upper: limb(0.022), fore: limb(0.019),
  }));

  // The person (rnnpb.demonstrator.UserBody: a kneeling adult facing the robot), drawn
  // translucent so the robot stays in view behind: torso, head, and each arm from the
  // shoulder to the hand the robot perceives (the elbow is placed for the look only).
  const skin = new THREE.MeshStandardMaterial({ color: 0xc9a88e, roughness: 0.7,
    transparent: true, opacity: 0.55 });
  const cloth = new THREE.MeshStandardMaterial({ color: 0x6d7f99, roughness: 0.8,
    transparent: true, opacity: 0.35 });
  const person = { parts: [], arms: [] };
  const userShoulders = () => (dash.state && dash.state.user_shoulders)
    || [[1, -0.19, 0.95], [1, 0.19, 0.95]];
  function buildPerson() {
    // Kneeling, as UserBody's shoulder height says: head, torso, thighs, shins on the floor.
    const [l, r] = userShoulders();
    const mid = [(l[0] + r[0]) / 2, (l[1] + r[1]) / 2, (l[2] + r[2]) / 2];
    const width = Math.abs(r[1] - l[1]), hips = mid[2] - 0.5;
    person.parts.push(add(new THREE.BoxGeometry(width + 0.04, 0.52, 0.16), cloth,
      [mid[0] + 0.03, mid[1], mid[2] - 0.24]));
    person.parts.push(add(new THREE.BoxGeometry(width - 0.04, hips - 0.1, 0.15), cloth,
      [mid[0] + 0.03, mid[1], 0.1 + (hips - 0.1) / 2]));                     // thighs
    person.parts.push(add(new THREE.BoxGeometry(width - 0.04, 0.1, 0.4), cloth,
      [mid[0] + 0.22, mid[1], 0.05]));                                       // shins
    person.parts.push(add(new THREE.CylinderGeometry(0.04, 0.045, 0.08, 14), skin,
      [mid[0] + 0.03, mid[1], mid[2] + 0.05]));
    person.parts.push(add(new THREE.SphereGeometry(0.09, 20, 14), skin,
      [mid[0] + 0.03, mid[1], mid[2] + 0.17]));
    for (let side = 0; side < 2; side++) {
      person.arms.push({ upper: limb(0.035, cloth), fore: limb(0.03, skin),
        shoulder: add(new THREE.SphereGeometry(0.045, 14, 10), cloth, [l, r][side]) });
    }
  }
  buildPerson();
  const userHands = [RED, BLUE].map((color) => add(new THREE.SphereGeometry(0.035, 20, 14),
    new THREE.MeshStandardMaterial({ color, roughness: 0.35 })));
  const UPPER = 0.3, FORE = 0.3;  // the person's arm (UserBody.arm_reach is about 0.62)
  function userElbow(s, h, side) {
    // Bend away from the body and down: the elbow of a relaxed arm reaching forward.
    const d = new THREE.Vector3().subVectors(h, s), len = Math.min(d.length(), UPPER + FORE - 1e-3);
    const along = d.clone().normalize();
    const out = new THREE.Vector3(side === 0 ? -0.6 : 0.6, -1, 0);
    out.addScaledVector(along, -out.dot(along)).normalize();
    const a = (UPPER * UPPER - FORE * FORE + len * len) / (2 * len);
    const bend = Math.sqrt(Math.max(UPPER * UPPER - a * a, 0));
    return s.clone().addScaledVector(along, a).addScaledVector(out, bend);
  }
  function placePersonArm(side, hand) {
    const arm = person.arms[side];
    arm.upper.visible = arm.fore.visible = !!hand;
    userHands[side].visible = !!hand;
    if (!hand) return;
    const s = v3(userShoulders()[side]), h = v3(hand), e = userElbow(s, h, side);
    placeLimb(arm.upper, s, e);
    placeLimb(arm.fore, e, h);
    userHands[side].position.copy(h);
  }

  const up = new THREE.Vector3(0, 1, 0);
  function placeLimb(mesh, a, b) {
    const d = new THREE.Vector3().subVectors(b, a);
    mesh.position.copy(a).addScaledVector(d, 0.5);
    mesh.scale.set(1, Math.max(d.length(), 1e-4), 1);
    mesh.quaternion.setFromUnitVectors(up, d.clone().normalize());
  }

  // Orbit: drag turns, wheel zooms (no controls library needed for this much). The first
  // view looks over the person's right shoulder at the robot, which faces it: the mirror.
  const VIEW = { azimuth: 0.95, elevation: 0.16, distance: 2.45 };
  let { azimuth, elevation, distance } = VIEW;
  const target = v3([0.45, 0, 0.62]);  // between the robot and the person
  function placeCamera() {
    camera.position.set(
      target.x + distance * Math.cos(elevation) * Math.sin(azimuth),
      target.y + distance * Math.sin(elevation),
      target.z + distance * Math.cos(elevation) * Math.cos(azimuth));
    camera.lookAt(target);
  }
  let dragging = null;
  renderer.domElement.addEventListener("pointerdown", (e) => {
    dragging = { x: e.clientX, y: e.clientY };
    renderer.domElement.setPointerCapture(e.pointerId);
  });
  renderer.domElement.addEventListener("pointermove", (e) => {
    if (!dragging) return;
    azimuth -= (e.clientX - dragging.x) * 0.008;
    elevation = Math.min(1.4, Math.max(-0.2, elevation + (e.clientY - dragging.y) * 0.006));
    dragging = { x: e.clientX, y: e.clientY };
    needsDraw = true;
  });
  renderer.domElement.addEventListener("pointerup", () => { dragging = null; });
  renderer.domElement.addEventListener("dblclick", () => {
    ({ azimuth, elevation, distance } = VIEW);
    needsDraw = true;
  });
  renderer.domElement.addEventListener("wheel", (e) => {
    e.preventDefault();
    distance = Math.min(5, Math.max(0.6, distance * Math.exp(e.deltaY * 0.001)));
    needsDraw = true;
  }, { passive: false });

  // The server sends one pose per step; the view eases from the previous pose to the newest
  // over one step, so the arms move smoothly (one step behind).
  let previous = null, current = null, received = 0;
  const restPose = () => {
    const shoulders = (dash.state && dash.state.robot.shoulders) || [[0, 0.095, 0.4], [0, -0.095, 0.4]];
    return { shoulders, elbows: shoulders.map((s) => [s[0], s[1], s[2] - 0.1]),
      hands: shoulders.map((s) => [s[0], s[1], s[2] - 0.21]), user: [null, null] };
  };
  function push(step) {
    const shoulders = dash.state.robot.shoulders;
    const pose = { shoulders, elbows: step.arms.elbows, hands: step.arms.hands,
      user: step.user_hands };
    previous = current || pose;
    current = pose;
    received = performance.now();
    needsDraw = true;
  }
  function clear() { previous = current = null; needsDraw = true; }
  function lerp(a, b, t) { return a.map((v, i) => v + (b[i] - v) * t); }

  // Draw only while something moves (easing between poses, turning the view), at most
  // about 30 times a second: an idle page costs no GPU or CPU.
  let lastDraw = 0, needsDraw = true;
  function frame(now) {
    requestAnimationFrame(frame);
    const dtMs = (dash.state ? dash.state.dt : 0.4) * 1000;
    const easing = current && now - received < dtMs + 50;
    if (!(needsDraw || easing || dragging) || now - lastDraw < 30) return;
    lastDraw = now;
    needsDraw = false;
    draw();
  }
  function draw() {
    const width = container.clientWidth, height = container.clientHeight;
    const canvas = renderer.domElement;
    if (canvas.width !== Math.floor(width * renderer.getPixelRatio())
        || canvas.height !== Math.floor(height * renderer.getPixelRatio())) {
      renderer.setSize(width, height);
      camera.aspect = width / Math.max(height, 1);
      camera.updateProjectionMatrix();
    }
    const dt = (dash.state ? dash.state.dt : 0.4) * 1000;
    const t = current ? Math.min(1, (performance.now() - received) / dt) : 1;
    const a = previous || restPose(), b = current || restPose();
    for (let side = 0; side < 2; side++) {
      const s = v3(b.shoulders[side]);
      const e = v3(lerp(a.elbows[side], b.elbows[side], t));
      const h = v3(lerp(a.hands[side], b.hands[side], t));
      const arm = arms[side];
      arm.shoulder.position.copy(s);
      arm.elbow.position.copy(e);
      arm.hand.position.copy(h);
      placeLimb(arm.upper, s, e);
      placeLimb(arm.fore, e, h);
      const user = b.user && b.user[side];
      const before = a.user && a.user[side];
      placePersonArm(side, user ? (before ? lerp(before, user, t) : user) : null);
    }
    placeCamera();
    renderer.render(scene, camera);
    dash.rendered3d += 1;
  }
  requestAnimationFrame(frame);
  return { push, clear };
})();
