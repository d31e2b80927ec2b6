// symkin view: the page's program (a module; THREE and OrbitControls come from the vendored three.js).
// The pose is computed by the model's generated JavaScript (globalThis.symkin[<model>]); this file
// only draws it.  Data from Python: the JSON in <script id="symkin-data">.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const data = JSON.parse(document.getElementById("symkin-data").textContent);
const model = globalThis.symkin[data.name];
const frameNames = data.kind === "serial" ? Object.keys(model.FUNCTIONS.frames.outputs) : [];
// a hybrid device's wrist links (device_frames), drawn from the platform centre to its TCP
const wristFrameNames = data.wrist ? Object.keys(model.FUNCTIONS.device_frames.outputs) : [];
// legs of any topology: the page solves their loop closure for (q, s) (data.home.s: the home assembly's s)
const solvesClosure = data.home.s !== undefined;
const legNames = solvesClosure ? Object.keys(model.FUNCTIONS.leg_joints.outputs) : [];

// ------------------------------------------------------------------ linear algebra (small dense)

/** Singular values of A (rows x cols), descending: one-sided Jacobi (Demmel & Veselic 1992). */
function singularValues(A) {
  let M = A.length >= A[0].length ? A.map((r) => r.slice()) : A[0].map((_, j) => A.map((r) => r[j]));
  const m = M.length, n = M[0].length;
  for (let sweep = 0; sweep < 60; sweep++) {
    let rotated = false;
    for (let p = 0; p < n - 1; p++) {
      for (let q = p + 1; q < n; q++) {
        let alpha = 0, beta = 0, gamma = 0;
        for (let i = 0; i < m; i++) {
          alpha += M[i][p] * M[i][p]; beta += M[i][q] * M[i][q]; gamma += M[i][p] * M[i][q];
        }
        if (Math.abs(gamma) <= 1e-15 * Math.sqrt(alpha * beta) || gamma === 0) continue;
        rotated = true;
        const zeta = (beta - alpha) / (2 * gamma);
        const t = Math.sign(zeta || 1) / (Math.abs(zeta) + Math.sqrt(1 + zeta * zeta));
        const c = 1 / Math.sqrt(1 + t * t), s = c * t;
        for (let i = 0; i < m; i++) {
          const x = M[i][p], y = M[i][q];
          M[i][p] = c * x - s * y; M[i][q] = s * x + c * y;
        }
      }
    }
    if (!rotated) break;
  }
  const sigma = [];
  for (let j = 0; j < n; j++) sigma.push(Math.hypot(...M.map((r) => r[j])));
  return sigma.sort((a, b) => b - a);
}

/** A^-1 by Gauss-Jordan elimination with partial pivoting; null if A is singular or not finite. */
function invert(A) {
  const n = A.length;
  const M = A.map((r, i) => [...r, ...r.map((_, j) => (i === j ? 1 : 0))]);
  for (let k = 0; k < n; k++) {
    let pivot = k;
    for (let i = k + 1; i < n; i++) if (Math.abs(M[i][k]) > Math.abs(M[pivot][k])) pivot = i;
    if (!(Math.abs(M[pivot][k]) > 0)) return null;
    [M[k], M[pivot]] = [M[pivot], M[k]];
    const d = M[k][k];
    for (let j = 0; j < 2 * n; j++) M[k][j] /= d;
    for (let i = 0; i < n; i++) {
      if (i === k) continue;
      const f = M[i][k];
      for (let j = 0; j < 2 * n; j++) M[i][j] -= f * M[k][j];
    }
  }
  return M.map((r) => r.slice(n));
}

function matmul(A, B) {
  return A.map((r) => B[0].map((_, j) => r.reduce((s, v, k) => s + v * B[k][j], 0)));
}

function determinant(A) {
  const n = A.length;
  const M = A.map((r) => r.slice());
  let det = 1;
  for (let k = 0; k < n; k++) {
    let pivot = k;
    for (let i = k + 1; i < n; i++) if (Math.abs(M[i][k]) > Math.abs(M[pivot][k])) pivot = i;
    if (M[pivot][k] === 0) return 0;
    if (pivot !== k) { [M[k], M[pivot]] = [M[pivot], M[k]]; det = -det; }
    det *= M[k][k];
    for (let i = k + 1; i < n; i++) {
      const f = M[i][k] / M[k][k];
      for (let j = k; j < n; j++) M[i][j] -= f * M[k][j];
    }
  }
  return det;
}

/** omega = E d(roll, pitch, yaw)/dt for R = Rz(yaw) Ry(pitch) Rx(roll) (symkin.mechanism.reach). */
function angularVelocityMatrix(pitch, yaw) {
  const cp = Math.cos(pitch), sp = Math.sin(pitch), cy = Math.cos(yaw), sy = Math.sin(yaw);
  return [[cy * cp, -sy, 0], [sy * cp, cy, 0], [-sp, 0, 1]];
}

/** The task Jacobian {raw, rated}: rated as the analyses rate it (symkin.analysis.mechanism.jacobian,
 *  parallel.ConstantOrientation), homogenized by the characteristic length where the task space mixes
 *  lengths and angles.  null where J^-1 is singular. */
function taskJacobian(state) {
  const c = data.conditioning;
  let J;
  if (data.kind === "serial") {
    J = call("jacobian", state.q);
  } else if (solvesClosure) {
    J = closureJacobian(state);
    if (J === null) return null;
    if (["roll", "pitch", "yaw"].every((a) => data.task_space.includes(a))) J = matmul(angularRates(state.p), J);
  } else if (c.twist) {  // a rotating platform: twist Jacobian diag(I, E) (J^-1)^-1, angle rates to omega by E
    const inverse = invert(call("inverse_jacobian", state.q, state.p));
    if (inverse === null) return null;
    J = matmul(angularRates(state.p), inverse);
  } else {
    J = call("jacobian", state.q, state.p);
  }
  const rated = c.length ? J.map((row, i) => (c.position_rows.includes(i) ? row.map((v) => v / c.length) : row)) : J;
  return { raw: J, rated };
}

/** diag(I, E): the task coordinates' rates with roll, pitch, yaw rates turned into angular velocity by E(p). */
function angularRates(p) {
  const angles = ["roll", "pitch", "yaw"];
  const pose = platformPose(p);
  const E = angularVelocityMatrix(pose.angles[1], pose.angles[2]);
  return data.task_space.map((row, i) => data.task_space.map((column, j) => {
    const [a, b] = [angles.indexOf(row), angles.indexOf(column)];
    return a < 0 || b < 0 ? (i === j ? 1 : 0) : E[a][b];
  }));
}

/** J = dp/dq of legs of any topology at an assembled (q, s, p) by the generated solver of the model's script
 *  (assembly_jacobian: the least-squares solution of [Phi_s Phi_p] (ds, dp) = -Phi_q dq by Householder QR, the C
 *  backend's <model>_assembly_jacobian and symkin.runtime.parallel.closure_velocities); null where the actuators do
 *  not determine the platform (a singularity). */
function closureJacobian(state) {
  const J = model.assembly_jacobian(state.q, state.s, state.p, designParameters(model.FUNCTIONS.closure_jacobians.parameters));
  return J.every((row) => row.every(Number.isFinite)) ? J : null;
}

/** The design's values of the parameters named (those the viewer holds). */
function designParameters(names) {
  return Object.fromEntries(names.filter((name) => state.params[name] !== undefined).map((name) => [name, state.params[name]]));
}

/** (q, s) at the pose p from the assembly (q, s) nearby by the generated solver of the model's script
 *  (assemble_inverse: Gauss-Newton on the closure, the C backend's <model>_assemble_inverse and
 *  symkin.runtime.parallel.solve_closure's rules) with the settings of symkin.analysis.closure_workspace
 *  (data.closure): {q, s} where the legs close (every row below closed times the pose's scale), else null. */
function solveClosure(q, s, p) {
  const { max_step: maxStep, tolerance, closed, iterations } = data.closure;
  const params = designParameters([...new Set([...model.FUNCTIONS.closure.parameters,
    ...model.FUNCTIONS.closure_jacobians.parameters])]);
  const solved = model.assemble_inverse(p, q, s, params, { max_iterations: iterations, tolerance, max_step: maxStep });
  const scale = Math.max(1, ...p.map(Math.abs));
  return solved.steps > 0 && solved.residual <= closed * scale ? { q: solved.q, s: solved.s } : null;
}

/** 1/kappa = sigma_min / sigma_max of a rated task Jacobian ({raw, rated}); null where J is missing or not finite. */
function inverseCondition(J) {
  if (!J || !J.rated.every((r) => r.every(Number.isFinite))) return null;
  const sigma = singularValues(J.rated);
  return sigma[sigma.length - 1] / sigma[0];
}

// ------------------------------------------------------------------ state and evaluation

/** model[name](...vectors, parameters): each function gets the design parameters it takes. */
function call(name, ...vectors) {
  const params = Object.fromEntries(model.FUNCTIONS[name].parameters.map((p) => [p, state.params[p]])
    .filter(([, v]) => v !== undefined));
  return model[name](...vectors, params);
}

/** A platform's position and roll, pitch, yaw from its task coordinates p (those it does not move in are 0). */
function platformPose(p) {
  const get = (name) => { const k = data.task_space.indexOf(name); return k < 0 ? 0 : p[k]; };
  return { position: ["x", "y", "z"].map(get), angles: ["roll", "pitch", "yaw"].map(get) };
}

const state = { q: data.home.q.slice(), p: data.home.p ? data.home.p.slice() : null,
  s: solvesClosure ? data.home.s.slice() : null,
  qw: data.home.qw ? data.home.qw.slice() : null,
  // no prototype: a parameter named like an Object.prototype member ("constructor") is only what is set
  params: Object.assign(Object.create(null), Object.fromEntries(data.parameters.map((p) => [p.name, p.value]))) };

function evaluate() {
  const out = { warnings: [] };
  if (data.kind === "serial") {
    const frames = call("frames", state.q);
    const tcp = call("fk", state.q);
    out.frames = [...frameNames.map((name) => frames[name]), tcp];
    out.tcp = [tcp[0][3], tcp[1][3], tcp[2][3]];
    out.points = [[0, 0, 0], ...out.frames.map((T) => [T[0][3], T[1][3], T[2][3]])];
  } else if (solvesClosure) {
    evaluateClosure(out);
  } else {
    const { joints, margin } = call("ik", state.p);
    state.q = joints;
    const unreachable = margin.map((m, i) => (m >= 0 ? null : i + 1)).filter((i) => i !== null);
    if (unreachable.length) out.warnings.push(`out of reach of leg ${unreachable.join(", ")}`);
    warnBeyondLimits(joints, out);
    const rows = unreachable.length ? null : call("leg_points", joints, state.p);
    out.legs = rows && rows.map((_, k) => rows.slice(3 * k, 3 * k + 3)).slice(0, rows.length / 3);
    platformFrame(out);
    if (data.wrist) evaluateWrist(out);
    if (model.singularities && !unreachable.length) {
      const { det_Jq, det_Jx } = call("singularities", joints, state.p);
      out.detJq = det_Jq; out.detJx = det_Jx;
    }
  }
  const J = out.warnings.length && data.kind === "parallel" ? null : taskJacobian(state);
  const inverseKappa = inverseCondition(J);
  if (inverseKappa !== null) {
    out.inverseKappa = inverseKappa;
    out.det = J.raw.length === J.raw[0].length ? determinant(J.raw) : null;
    if (!(out.inverseKappa >= data.singular_threshold)) {
      out.warnings.push(`near a singular configuration (1/kappa < ${data.singular_threshold})`);
    }
  }
  return out;
}

/** Legs of any topology at state.p: the closure solved from the last assembly (kept where the legs do not close
 *  there, so that moving back finds them again), every leg's joints, the platform's frame. */
function evaluateClosure(out) {
  const solved = solveClosure(state.q, state.s, state.p);
  if (solved === null) {
    out.warnings.push("the legs do not close at this pose from the last assembly (out of reach)");
  } else {
    // an angle is shown as its first representative at or above its lower limit (symkin.analysis.limits)
    const turn = 2 * Math.PI;
    const wrap = (v, c) => (c.revolute ? c.lower + (((v - c.lower) % turn) + turn) % turn : v);
    Object.assign(state, { q: solved.q.map((v, i) => wrap(v, data.coordinates[i])), s: solved.s });
    warnBeyondLimits(state.q, out);
    const joints = call("leg_joints", state.q, state.s);
    out.legs = legNames.map((name) => joints[name]);
  }
  platformFrame(out);
}

/** A warning naming the actuators whose joints q lie beyond their limits, if any. */
function warnBeyondLimits(q, out) {
  const beyond = data.coordinates.map((c, i) => (q[i] < c.lower || q[i] > c.upper ? c.label : null))
    .filter((n) => n !== null);
  if (beyond.length) out.warnings.push(`beyond the limits of ${beyond.join(", ")}`);
}

/** The platform's position (the TCP shown) and frame at state.p. */
function platformFrame(out) {
  const pose = platformPose(state.p);
  out.tcp = pose.position;
  const [roll, pitch, yaw] = pose.angles;
  const R = new THREE.Matrix4().makeRotationFromEuler(new THREE.Euler(roll, pitch, yaw, "ZYX"));
  const e = R.elements;  // column-major
  out.frames = [[[e[0], e[4], e[8], out.tcp[0]], [e[1], e[5], e[9], out.tcp[1]], [e[2], e[6], e[10], out.tcp[2]],
    [0, 0, 0, 1]]];
}

/** A hybrid device's wrist on the platform at state.p: its links' frames and TCP (the TCP the page shows
 *  becomes the wrist's), and the wrist's 1/kappa from the angular rows of device_jacobian in its columns. */
function evaluateWrist(out) {
  const frames = call("device_frames", state.p, state.qw);
  const tcp = call("device_fk", state.p, state.qw);
  const wristFrames = [...wristFrameNames.map((name) => frames[name]), tcp];
  out.wrist = [out.tcp, ...wristFrames.map((T) => [T[0][3], T[1][3], T[2][3]])];
  out.frames.push(...wristFrames);
  out.tcp = out.wrist[out.wrist.length - 1];
  const J = call("device_jacobian", state.p, state.qw);
  const angular = J.slice(3).map((row) => row.slice(data.task_space.length));
  out.wristKappa = inverseCondition({ raw: angular, rated: angular });
}

// ------------------------------------------------------------------ drawing

const viridis = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383],
  [0.993, 0.906, 0.144]];
function colour(t) {
  const x = Math.min(Math.max(t, 0), 1) * (viridis.length - 1);
  const k = Math.min(Math.floor(x), viridis.length - 2), f = x - k;
  return viridis[k].map((v, i) => v + f * (viridis[k + 1][i] - v));
}

const canvas = document.getElementById("view");
let renderer = null;
try {
  renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
} catch (error) {
  document.getElementById("no-webgl").hidden = false;
}
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf7f7f5);
const camera = new THREE.PerspectiveCamera(40, 1, data.scale / 100, data.scale * 100);
camera.up.set(0, 0, 1);
const target = new THREE.Vector3(...data.view_target);
camera.position.set(target.x + 1.3 * data.scale, target.y - 1.6 * data.scale, target.z + 0.9 * data.scale);
let controls = null;
if (renderer) {
  controls = new OrbitControls(camera, canvas);
  controls.target.copy(target);
  controls.update();
  controls.addEventListener("change", render);
}
const grid = new THREE.GridHelper(4 * data.scale, 20, 0xbbbbbb, 0xdddddd);
grid.rotation.x = Math.PI / 2;
scene.add(grid);

const axisLength = data.scale * 0.12;
function triad(size) {
  const group = new THREE.Group();
  const colours = [0xd62728, 0x2ca02c, 0x1f77b4];
  for (let k = 0; k < 3; k++) {
    const direction = new THREE.Vector3(k === 0 ? 1 : 0, k === 1 ? 1 : 0, k === 2 ? 1 : 0);
    const geometry = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), direction.multiplyScalar(size)]);
    group.add(new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: colours[k] })));
  }
  group.matrixAutoUpdate = false;
  scene.add(group);
  return group;
}
function setPose(object, T) {
  object.matrix.set(T[0][0], T[0][1], T[0][2], T[0][3], T[1][0], T[1][1], T[1][2], T[1][3],
    T[2][0], T[2][1], T[2][2], T[2][3], 0, 0, 0, 1);
}

scene.add(new THREE.AmbientLight(0xffffff, 1.2));
const light = new THREE.DirectionalLight(0xffffff, 2.0);
light.position.set(1, -2, 3);
scene.add(light);
const linkMaterial = new THREE.MeshLambertMaterial({ color: 0x4d5b6a });
const baseMaterial = new THREE.MeshLambertMaterial({ color: 0x8c8c8c });
const platformMaterial = new THREE.MeshLambertMaterial({ color: 0x1f77b4 });
const links = new THREE.Group();
scene.add(links);
const jointMaterial = new THREE.MeshLambertMaterial({ color: 0xff7f0e });
const jointGeometry = new THREE.SphereGeometry(data.scale * 0.012, 12, 8);
const frameCount = data.kind === "serial" ? frameNames.length + 1 : 1 + (data.wrist ? wristFrameNames.length + 1 : 0);
const triads = Array.from({ length: frameCount }, (_, k) => triad(k === frameCount - 1 ? axisLength * 1.6 : axisLength));
triad(axisLength * 1.2);  // the base frame

const traceLength = 600;
const trace = new THREE.BufferGeometry();
trace.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * traceLength), 3));
trace.setDrawRange(0, 0);
scene.add(new THREE.Line(trace, new THREE.LineBasicMaterial({ color: 0x9467bd })));
let traceCount = 0;

let cloud = null;

/** Show points (k, 3) coloured by their 1/kappa, scaled to the largest; the colour bar follows. */
function showCloud(points, values) {
  const top = Math.max(...values, 1e-12);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(points.flat(), 3));
  geometry.setAttribute("color", new THREE.Float32BufferAttribute(values.flatMap((v) => colour(v / top)), 3));
  if (cloud === null) {
    cloud = new THREE.Points(geometry, new THREE.PointsMaterial({ size: data.scale * 0.012, vertexColors: true }));
    scene.add(cloud);
  } else {
    cloud.geometry.dispose();
    cloud.geometry = geometry;
  }
  const ticks = document.getElementById("colour-ticks").children;
  [0, top / 2, top].forEach((v, k) => { ticks[k].textContent = v.toFixed(2); });
  cloud.userData = { points, values };
}
if (data.cloud.points.length) showCloud(data.cloud.points, data.cloud.inverse_kappa);

/** The cloud again for the current design: the same samples (joint configurations; a pose platform's
 *  centres at the home orientation) through the generated fk (ik) and the rated Jacobian.  Samples
 *  that no longer assemble are left out; the characteristic length stays the one of the design at load. */
function recomputeCloud() {
  const points = [], values = [];
  const orientation = data.kind === "parallel" ? data.home.p.slice(3) : [];
  data.cloud.samples.forEach((sample) => {
    let point, pose;
    if (data.kind === "serial") {
      const T = call("fk", sample);
      point = [T[0][3], T[1][3], T[2][3]];
      pose = { q: sample };
    } else if (solvesClosure) {  // the cell's pose, solved again from its (q, s) at load
      const p = [...sample.p];
      const solved = solveClosure(sample.q, sample.s, p);
      if (solved === null) return;
      point = platformPose(p).position;
      pose = { ...solved, p };
    } else if (!data.conditioning.twist) {
      const { position, margin } = call("fk", sample);
      if (!(margin >= 0)) return;
      point = platformPose(position).position;
      pose = { q: sample, p: position };
    } else {
      const p = [...sample, ...orientation];
      const { joints, margin } = call("ik", p);
      if (!margin.every((m) => m >= 0)) return;
      point = sample;
      pose = { q: joints, p };
    }
    const value = inverseCondition(taskJacobian(pose));
    points.push(point);
    values.push(value !== null && Number.isFinite(value) ? value : 0);
  });
  showCloud(points, values);
  document.getElementById("cloud-note").hidden = true;
  render();
}

const unitCylinder = new THREE.CylinderGeometry(1, 1, 1, 12);
const yAxis = new THREE.Vector3(0, 1, 0);

/** A solid rod from a to b (links, legs); a line where the two points coincide. */
function rod(a, b, radius, material) {
  const start = new THREE.Vector3(...a), end = new THREE.Vector3(...b);
  const length = start.distanceTo(end);
  if (!(length > 1e-9)) return;
  const mesh = new THREE.Mesh(unitCylinder, material);
  mesh.position.copy(start).add(end).multiplyScalar(0.5);
  mesh.quaternion.setFromUnitVectors(yAxis, end.clone().sub(start).divideScalar(length));
  mesh.scale.set(radius, length, radius);
  links.add(mesh);
}

function chain(points, radius, material) {
  points.slice(1).forEach((p, k) => rod(points[k], p, radius, material));
}

function joint(p) {
  const ball = new THREE.Mesh(jointGeometry, jointMaterial);
  ball.position.set(...p);
  links.add(ball);
}

function draw(out) {
  links.clear();
  const radius = data.scale * 0.006;
  if (out.points && data.tree) {  // points: the base, each link's frame, the TCP
    data.tree.parents.forEach((p, k) => rod(out.points[p + 1], out.points[k + 1], radius, linkMaterial));
    rod(out.points[data.tree.tip + 1], out.points[out.points.length - 1], radius, linkMaterial);
    out.points.slice(0, -1).forEach(joint);
  } else if (out.points) {
    chain(out.points, radius, linkMaterial);
    out.points.slice(0, -1).forEach(joint);
  }
  if (out.legs) {
    out.legs.forEach((leg) => chain(leg, radius, linkMaterial));
    const ring = (end) => [...out.legs.map(end), end(out.legs[0])];  // through each leg's first or last point
    chain(ring((leg) => leg[0]), radius * 1.5, baseMaterial);
    chain(ring((leg) => leg[leg.length - 1]), radius * 1.2, platformMaterial);
    out.legs.flat().forEach(joint);
  }
  if (out.wrist) {
    chain(out.wrist, radius, linkMaterial);
    out.wrist.slice(1, -1).forEach(joint);
  }
  out.frames.forEach((T, k) => setPose(triads[k], T));
  const position = trace.getAttribute("position");
  if (traceCount === traceLength) position.array.copyWithin(0, 3);
  else traceCount += 1;
  position.array.set(out.tcp, 3 * (traceCount - 1));
  position.needsUpdate = true;
  trace.setDrawRange(0, traceCount);
  render();
}

function render() {
  if (!renderer) return;
  const width = canvas.clientWidth, height = canvas.clientHeight;
  if (canvas.width !== width || canvas.height !== height) {
    renderer.setSize(width, height, false);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
  }
  renderer.render(scene, camera);
}
window.addEventListener("resize", render);

// ------------------------------------------------------------------ controls and read-outs

function format(value, digits) {
  return Number.isFinite(value) ? value.toFixed(digits) : "-";
}

function show(out) {
  const tcp = document.getElementById("tcp");
  ["x", "y", "z"].forEach((axis, k) => { tcp.dataset[axis] = String(out.tcp[k]); });
  tcp.textContent = out.tcp.map((v) => format(1000 * v, 3)).join(", ") + " mm";
  const kappa = document.getElementById("inverse-kappa");
  kappa.dataset.value = String(out.inverseKappa ?? NaN);
  kappa.textContent = format(out.inverseKappa, 4);
  const det = document.getElementById("det");
  det.dataset.value = String(out.det ?? NaN);
  det.textContent = out.det === null || out.det === undefined ? "-" : out.det.toPrecision(4);
  if (out.detJq !== undefined) {
    document.getElementById("det-parallel").textContent =
      `det J_q = ${out.detJq.toPrecision(4)}, det J_x = ${out.detJx.toPrecision(4)}`;
  }
  const warning = document.getElementById("warning");
  warning.textContent = out.warnings.join("; ");
  warning.hidden = out.warnings.length === 0;
  if (data.wrist) {
    const wrist = document.getElementById("wrist-kappa");
    wrist.dataset.value = String(out.wristKappa ?? NaN);
    wrist.textContent = format(out.wristKappa, 4);
  }
  if (data.kind === "parallel") {
    document.getElementById("joints").textContent = state.q.map((v, i) =>
      `${data.coordinates[i].label} = ${format(v / data.coordinates[i].scale, 2)} ${data.coordinates[i].unit}`).join(", ");
  }
}

function update() {
  const out = evaluate();
  draw(out);
  show(out);
  document.body.dataset.updates = String(Number(document.body.dataset.updates || 0) + 1);
}

function slider(container, spec, value, onChange) {
  const row = document.createElement("label");
  row.className = "slider";
  const name = document.createElement("span");
  name.textContent = spec.label;
  const input = document.createElement("input");
  Object.assign(input, { type: "range", min: spec.lower, max: spec.upper, step: spec.step, value });
  input.id = spec.id;
  const shown = document.createElement("output");
  const refresh = () => { shown.textContent = `${Number(input.value).toFixed(spec.digits)} ${spec.unit}`; };
  input.addEventListener("input", () => { refresh(); onChange(Number(input.value)); update(); });
  refresh();
  row.append(name, input, shown);
  container.append(row);
}

const sliders = document.getElementById("sliders");
if (data.kind === "serial") {
  data.coordinates.forEach((c, i) => slider(sliders, { id: `joint-${c.name}`, label: c.label, lower: c.lower / c.scale,
    upper: c.upper / c.scale, step: c.step, unit: c.unit, digits: 1 }, state.q[i] / c.scale,
  (v) => { state.q[i] = v * c.scale; }));
} else {
  data.task.forEach((t, i) => slider(sliders, { id: `task-${t.name}`, label: t.name, lower: t.lower / t.scale,
    upper: t.upper / t.scale, step: t.step, unit: t.unit, digits: 1 }, state.p[i] / t.scale,
  (v) => { state.p[i] = v * t.scale; }));
}
if (data.wrist) {
  data.wrist.forEach((c, i) => slider(document.getElementById("wrist-sliders"), { id: `wrist-${c.name}`, label: c.label,
    lower: c.lower / c.scale, upper: c.upper / c.scale, step: c.step, unit: c.unit, digits: 1 }, state.qw[i] / c.scale,
  (v) => { state.qw[i] = v * c.scale; }));
}
const design = document.getElementById("design");
data.parameters.forEach((p) => slider(design, { id: `param-${p.name}`, label: p.name, lower: p.lower / p.scale,
  upper: p.upper / p.scale, step: p.step, unit: p.unit, digits: 1 }, p.value / p.scale, (v) => {
  state.params[p.name] = v * p.scale;
  const changed = data.parameters.some((q) => state.params[q.name] !== q.value);
  document.getElementById("cloud-note").hidden = !changed;
}));

const toggle = document.getElementById("show-cloud");
toggle.disabled = cloud === null;
toggle.addEventListener("change", () => {
  if (cloud) cloud.visible = toggle.checked;
  document.getElementById("colour-bar").hidden = !toggle.checked;
  render();
});
document.getElementById("clear-trace").addEventListener("click", () => { traceCount = 0; trace.setDrawRange(0, 0); render(); });

update();
document.getElementById("recompute-cloud").addEventListener("click", recomputeCloud);
window.symkinView = { state, evaluate, update, get cloud() { return cloud; }, recomputeCloud, singularValues, invert };
document.body.dataset.ready = "1";
