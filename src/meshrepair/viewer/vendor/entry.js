// The parts of three.js the meshrepair viewer uses, bundled once into three.bundle.min.js
// (see README.md in this folder). Add an export here when viewer.js needs more of three.
export {
  AmbientLight, Box3, BufferAttribute, BufferGeometry, Color, ColorManagement, DirectionalLight,
  DoubleSide, LinearSRGBColorSpace,
  LineBasicMaterial, LineSegments, Mesh, MeshBasicMaterial, MeshLambertMaterial,
  PerspectiveCamera, REVISION, Scene, Sphere, Vector3, WebGLRenderer,
} from "three";
export { OrbitControls } from "three/addons/controls/OrbitControls.js";
