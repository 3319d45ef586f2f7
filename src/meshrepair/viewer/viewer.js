// meshrepair 3-D viewer: side-by-side panes with linked cameras (see meshrepair/viewer/page.py
// for the page layout). "three" is resolved by the page's import map to the vendored bundle.
import {
  AmbientLight, BufferAttribute, BufferGeometry, Color, ColorManagement, DirectionalLight,
  DoubleSide, LinearSRGBColorSpace,
  LineBasicMaterial, LineSegments, Mesh, MeshBasicMaterial, MeshLambertMaterial, OrbitControls,
  PerspectiveCamera, REVISION, Scene, Vector3, WebGLRenderer,
} from "three";

const root = document.getElementById("mr-viewer");
const data = JSON.parse(document.getElementById("mr-viewer-data").textContent);
const FOV = 30; // vertical field of view, degrees
const GREY = [0.80, 0.80, 0.82];
const NAN_GREY = [0.55, 0.55, 0.55];

function el(tag, attrs = {}, text = null) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== null) e.textContent = text;
  return e;
}
function bytes(s) {
  const bin = atob(s);
  const out = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out;
}
const f32 = (s) => { const b = bytes(s); return new Float32Array(b.buffer, 0, b.length >> 2); };
const u32 = (s) => { const b = bytes(s); return new Uint32Array(b.buffer, 0, b.length >> 2); };
// Shading is done on the sRGB values themselves, no colour management: the same colours and
// the same Lambert head-light shading (ambient 0.18 + 0.82 cos) as meshrepair.render's PNGs.
ColorManagement.enabled = false;
const fmt = (x) => (Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-3 && x !== 0)
  ? x.toExponential(2) : String(Number(x.toPrecision(3))));
const hex = (rgb) => "#" + rgb.map((c) => c.toString(16).padStart(2, "0")).join("");

// ---------------------------------------------------------------------------------------------
// colour tables: per scalar name, sRGB bytes -> floats for the vertex colours

const specs = {};
for (const [name, s] of Object.entries(data.scalars)) {
  if (s.categories) {
    specs[name] = { ...s, linear: s.colors.map((c) => c.map((x) => x / 255)) };
  } else {
    const lut = bytes(s.lut);
    const linear = new Float32Array(lut.length);
    for (let i = 0; i < lut.length; i++) linear[i] = lut[i] / 255;
    specs[name] = { ...s, lutBytes: lut, linear };
  }
}

function fillColours(out, values, spec) {
  const n = out.length / 3;
  for (let i = 0; i < n; i++) {
    let c = GREY;
    if (values && spec) {
      const v = values[i];
      c = NAN_GREY;
      if (Number.isFinite(v)) {
        if (spec.categories) {
          const k = spec.categories.indexOf(v);
          if (k >= 0) c = spec.linear[k];
        } else {
          const t = Math.min(1, Math.max(0, (v - spec.lo) / (spec.hi - spec.lo)));
          const j = 3 * Math.round(t * 255);
          out[3 * i] = spec.linear[j]; out[3 * i + 1] = spec.linear[j + 1];
          out[3 * i + 2] = spec.linear[j + 2];
          continue;
        }
      }
    }
    out[3 * i] = c[0]; out[3 * i + 1] = c[1]; out[3 * i + 2] = c[2];
  }
}

// ---------------------------------------------------------------------------------------------
// page structure

root.textContent = "";
const bar = el("div", { class: "mr-controls" });
const colorSel = el("select", { "data-mr": "color", "aria-label": "colour by" });
colorSel.append(el("option", { value: "" }, "none (grey)"));
for (const name of Object.keys(data.scalars)) colorSel.append(el("option", { value: name }, name));
const lbl = (text, input) => { const l = el("label"); l.append(input, " " + text); return l; };
const colorLabel = el("label", {}, "colour ");
colorLabel.append(colorSel);
bar.append(colorLabel);
const shadingSel = el("select", { "data-mr": "shading", "aria-label": "shading" });
shadingSel.append(el("option", { value: "flat" }, "flat shading"),
  el("option", { value: "smooth" }, "smooth shading"));
bar.append(shadingSel);
const wireBox = el("input", { type: "checkbox", "data-mr": "wireframe" });
bar.append(lbl("wireframe", wireBox));
const hasSharp = data.panes.some((p) => p.sharp !== undefined);
const hasHl = data.panes.some((p) => p.highlight !== undefined);
const sharpBox = el("input", { type: "checkbox", "data-mr": "sharp" });
if (hasSharp) bar.append(lbl("sharp edges (M_E)", sharpBox));
const hlBox = el("input", { type: "checkbox", "data-mr": "highlight" });
hlBox.checked = true;
if (hasHl) {
  const names = [...new Set(data.panes.filter((p) => p.highlight !== undefined)
    .map((p) => p.highlightLabel))];
  bar.append(lbl("highlight " + names.join(" / "), hlBox));
}
const resetBtn = el("button", { type: "button", "data-mr": "reset" }, "reset view");
bar.append(resetBtn);
const legend = el("div", { class: "mr-legend" });
const panesDiv = el("div", { class: "mr-panes" });
root.append(bar, legend, panesDiv);
const help = el("p", { class: "mr-help" }, "Drag to orbit, right-drag (or shift/ctrl-drag) to "
  + "pan, wheel to zoom; the cameras of all panes move together. three.js r" + REVISION + ".");
root.append(help);

// ---------------------------------------------------------------------------------------------
// panes

const panes = [];
let syncing = false;
let pending = false;
const state = { ready: false, frames: 0, errors: [] };

function requestRender() {
  if (pending) return;
  pending = true;
  requestAnimationFrame(() => {
    pending = false;
    for (const p of panes) p.renderer.render(p.scene, p.camera);
    state.frames += 1;
  });
}

function clipPlanes(p) {
  const d = p.camera.position.distanceTo(p.controls.target);
  p.camera.near = Math.max(d * 0.01, data.scene.radius * 1e-5);
  p.camera.far = d + 4 * data.scene.radius;
  p.camera.updateProjectionMatrix();
}

function onChange(src) {
  if (syncing) return;
  syncing = true;
  try {
    for (const p of panes) {
      if (p !== src) {
        p.camera.position.copy(src.camera.position);
        p.camera.quaternion.copy(src.camera.quaternion);
        p.controls.target.copy(src.controls.target);
        p.controls.update();
      }
      clipPlanes(p);
    }
  } finally {
    syncing = false;
  }
  requestRender();
}

function makePane(info) {
  const div = el("div", { class: "mr-pane" });
  div.append(el("h3", {}, info.title));
  let note = `${info.nV.toLocaleString("en")} vertices, ${info.nF.toLocaleString("en")} faces`;
  if (info.highlight !== undefined) note += `; ${info.highlightCount} ${info.highlightLabel}`;
  if (info.sharp !== undefined) note += `; ${info.sharpCount} sharp edges`;
  div.append(el("p", { class: "mr-info" }, note));
  if (info.decimated) {
    div.append(el("p", { class: "mr-decimated" }, `Shown decimated (vertex clustering) to `
      + `${info.shownF.toLocaleString("en")} of ${info.nF.toLocaleString("en")} faces to stay `
      + `fast; the mesh itself is not changed.`));
  }
  const holder = el("div", { class: "mr-canvas" });
  div.append(holder);
  panesDiv.append(div);

  const renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.outputColorSpace = LinearSRGBColorSpace;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  holder.append(renderer.domElement);
  const scene = new Scene();
  scene.background = new Color(0xffffff);
  const geom = new BufferGeometry();
  const pos = new BufferAttribute(f32(info.positions), 3);
  geom.setAttribute("position", pos);
  geom.setIndex(new BufferAttribute(u32(info.indices), 1));
  geom.computeVertexNormals();
  const colours = new BufferAttribute(new Float32Array(pos.count * 3), 3);
  geom.setAttribute("color", colours);
  const material = new MeshLambertMaterial({
    color: 0xffffff, vertexColors: true, side: DoubleSide, flatShading: true,
    polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
  });
  scene.add(new Mesh(geom, material));
  const wire = new Mesh(geom, new MeshBasicMaterial({ color: 0x222222, wireframe: true }));
  wire.visible = false;
  scene.add(wire);
  let hl = null;
  if (info.highlight !== undefined) {
    const faces = u32(info.highlight);
    const idx = geom.index.array;
    const sub = new Uint32Array(faces.length * 3);
    for (let k = 0; k < faces.length; k++) {
      sub[3 * k] = idx[3 * faces[k]]; sub[3 * k + 1] = idx[3 * faces[k] + 1];
      sub[3 * k + 2] = idx[3 * faces[k] + 2];
    }
    const hg = new BufferGeometry();
    hg.setAttribute("position", pos);
    hg.setIndex(new BufferAttribute(sub, 1));
    hl = new Mesh(hg, new MeshLambertMaterial({
      color: 0x2f6bf2, side: DoubleSide, flatShading: true,
    }));
    scene.add(hl);
  }
  let sharp = null;
  if (info.sharp !== undefined) {
    const sg = new BufferGeometry();
    sg.setAttribute("position", pos);
    sg.setIndex(new BufferAttribute(u32(info.sharp), 1));
    sharp = new LineSegments(sg, new LineBasicMaterial({ color: 0x111111 }));
    sharp.visible = false;
    scene.add(sharp);
  }
  const camera = new PerspectiveCamera(FOV, 1, 0.01, 100);
  const light = new DirectionalLight(0xffffff, 0.82 * Math.PI);
  light.position.set(0, 0, 0);
  light.target.position.set(0, 0, -1);
  camera.add(light, light.target);
  scene.add(camera, new AmbientLight(0xffffff, 0.18 * Math.PI));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(...data.scene.center);
  const p = { info, div, holder, renderer, scene, camera, controls, geom, colours, material,
    wire, hl, sharp };
  controls.addEventListener("change", () => onChange(p));
  panes.push(p);
  return p;
}

// The canvas' CSS width is 100 % of its pane (so panes can shrink); its drawing buffer is
// resized to the pane's width here, on load and on every window resize.
function layout() {
  const h = data.height;
  for (const p of panes) {
    const w = Math.max(200, Math.floor(p.holder.clientWidth || 400));
    p.renderer.setSize(w, h, false);
    p.renderer.domElement.style.height = h + "px";
    p.camera.aspect = w / h;
    p.camera.updateProjectionMatrix();
  }
  requestRender();
}

// ---------------------------------------------------------------------------------------------
// toggles

function setColour(name) {
  const spec = name ? specs[name] : null;
  for (const p of panes) {
    let vals = null; // no colouring: grey; a pane without this scalar: darker grey
    if (name) {
      vals = p.info.scalars[name] !== undefined ? f32(p.info.scalars[name])
        : new Float32Array(p.colours.count).fill(NaN);
    }
    fillColours(p.colours.array, vals, spec);
    p.colours.needsUpdate = true;
  }
  legend.textContent = "";
  if (spec && spec.categories) {
    legend.append(el("span", {}, name + ": "));
    spec.categories.forEach((c, k) => {
      const box = el("span", { class: "mr-swatch", style: `background:${hex(spec.colors[k])}` });
      legend.append(box, el("span", {}, ` ${fmt(c)}  `));
    });
  } else if (spec) {
    const stops = [];
    for (let k = 0; k <= 8; k++) {
      const j = 3 * Math.round((k / 8) * 255);
      stops.push(hex([spec.lutBytes[j], spec.lutBytes[j + 1], spec.lutBytes[j + 2]]));
    }
    legend.append(el("span", {}, `${name}: ${fmt(spec.lo)} `),
      el("span", { class: "mr-ramp", style: `background:linear-gradient(to right,${stops})` }),
      el("span", {}, ` ${fmt(spec.hi)} (2-98 % range of all panes; grey: no value)`));
  }
  requestRender();
}

function setShading(mode) {
  for (const p of panes) {
    for (const m of [p.material, p.hl && p.hl.material]) {
      if (!m) continue;
      m.flatShading = mode === "flat";
      m.needsUpdate = true;
    }
  }
  requestRender();
}

function setVisible(key, on) {
  for (const p of panes) if (p[key]) p[key].visible = on;
  requestRender();
}

// Aim every camera at a sphere (center, radius), looking against `normal` (or keeping the
// current direction): the sphere fills the smaller side of the pane.
function goTo(region) {
  const p0 = panes[0];
  const c = new Vector3(...region.center);
  let dir = region.normal ? new Vector3(...region.normal)
    : p0.camera.position.clone().sub(p0.controls.target);
  if (dir.lengthSq() < 1e-30) dir = new Vector3(0, 0, 1);
  dir.normalize();
  if (Math.abs(dir.y) > 0.999) dir.set(dir.x + 1e-3, dir.y, dir.z + 1e-3).normalize();
  const half = Math.PI * FOV / 360;
  const hfov = Math.atan(Math.tan(half) * Math.min(1, p0.camera.aspect));
  const dist = (region.radius * 1.25) / Math.sin(Math.min(half, hfov));
  p0.controls.target.copy(c);
  p0.camera.position.copy(c).addScaledVector(dir, dist);
  p0.camera.up.set(0, 1, 0);
  p0.camera.lookAt(c);
  syncing = true;
  p0.controls.update();
  syncing = false;
  onChange(p0);
}

function resetView() {
  goTo({ center: data.scene.center, radius: data.scene.radius / 1.25, normal: [0, 0, 1] });
}

// ---------------------------------------------------------------------------------------------
// region list

function regionList() {
  if (!data.regions.length) return;
  const box = el("div", { class: "mr-regions" });
  box.append(el("h3", {}, "Holes and regions"));
  const table = el("table");
  const head = el("tr");
  head.append(el("th", {}, ""), el("th", {}, "region"), el("th", {}, "what happened"));
  table.append(head);
  data.regions.forEach((r, k) => {
    const tr = el("tr");
    const btn = el("button", { type: "button", class: "mr-goto", "data-region": String(k) },
      "go to");
    btn.addEventListener("click", () => goTo(r));
    const td = el("td");
    td.append(btn);
    tr.append(td, el("td", {}, r.name), el("td", {}, r.detail || ""));
    table.append(tr);
  });
  box.append(table);
  root.append(box);
}

// ---------------------------------------------------------------------------------------------
// start

try {
  for (const info of data.panes) makePane(info);
  regionList();
  colorSel.addEventListener("change", () => setColour(colorSel.value));
  shadingSel.addEventListener("change", () => setShading(shadingSel.value));
  wireBox.addEventListener("change", () => setVisible("wire", wireBox.checked));
  sharpBox.addEventListener("change", () => setVisible("sharp", sharpBox.checked));
  hlBox.addEventListener("change", () => setVisible("hl", hlBox.checked));
  resetBtn.addEventListener("click", resetView);
  window.addEventListener("resize", layout);
  const first = Object.keys(data.scalars).find((n) => n.toLowerCase().includes("curvature"));
  colorSel.value = first || "";
  setColour(colorSel.value);
  layout();
  resetView();
  state.ready = true;
} catch (err) {
  state.errors.push(String(err));
  root.prepend(el("p", { class: "mr-error" }, "The 3-D viewer could not start: " + err
    + " (it needs WebGL; the pictures and tables of this page do not)."));
  console.error(err);
}

window.meshrepairViewer = {
  state,
  panes,
  goTo: (k) => goTo(data.regions[k]),
  resetView,
  setColour,
  cameras: () => panes.map((p) => ({
    position: p.camera.position.toArray(),
    target: p.controls.target.toArray(),
    quaternion: p.camera.quaternion.toArray(),
  })),
  regions: data.regions,
};
