// The 3D view: the job's voxels as the surface between filled and empty
// voxels (in a colour job, each voxel in its colour), a distance field's
// zero level set (surface_nets.js), or a palette job's reconstruction,
// orbitable with the mouse (three.js). Regions of the report are shown as
// boxes.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/OrbitControls.js';
import { STLLoader } from 'three/addons/STLLoader.js';

// Grids above this many voxels are not drawn whole in a browser tab.
export const MAX_VIEW_VOXELS = 64 * 1024 * 1024;

const FACES = [
  // neighbour offset, then the quad's corners (voxel-local, counter-clockwise seen from outside)
  { d: [1, 0, 0], c: [[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]] },
  { d: [-1, 0, 0], c: [[0, 0, 0], [0, 0, 1], [0, 1, 1], [0, 1, 0]] },
  { d: [0, 1, 0], c: [[0, 1, 0], [0, 1, 1], [1, 1, 1], [1, 1, 0]] },
  { d: [0, -1, 0], c: [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]] },
  { d: [0, 0, 1], c: [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]] },
  { d: [0, 0, -1], c: [[0, 0, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0]] },
];

// The boundary faces of the filled voxels: `filled(i)` for voxel index i
// (x fastest), `colourOf(i)` an [r, g, b] in 0..1 or null for grey.
export function voxelSurface(dims, filled, colourOf) {
  const [nx, ny, nz] = dims;
  const positions = [], normals = [], colours = [];
  const at = (i, j, k) => i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz && filled(i + nx * (j + ny * k));
  for (let k = 0; k < nz; ++k)
    for (let j = 0; j < ny; ++j)
      for (let i = 0; i < nx; ++i) {
        const index = i + nx * (j + ny * k);
        if (!filled(index)) continue;
        const rgb = colourOf ? colourOf(index) : null;
        for (const f of FACES) {
          if (at(i + f.d[0], j + f.d[1], k + f.d[2])) continue;
          for (const q of [0, 1, 2, 0, 2, 3]) {
            const c = f.c[q];
            positions.push(i + c[0], j + c[1], k + c[2]);
            normals.push(...f.d);
            if (rgb) colours.push(...rgb);
          }
        }
      }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.setAttribute('normal', new THREE.Float32BufferAttribute(normals, 3));
  if (colours.length) geometry.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
  return geometry;
}

// Which voxels a job's raw volume fills, by its value type.
export function filledTest(bytes, valueType, mode) {
  switch (valueType) {
    case 'f32': {
      const v = new Float32Array(bytes);
      return mode === 'sdf' ? (i) => v[i] < 0 : (i) => v[i] >= 0.5;
    }
    case 'rgba8': {
      const v = new Uint8Array(bytes);
      return (i) => v[4 * i + 3] > 0;
    }
    case 'u8': {
      const v = new Uint8Array(bytes);
      return mode === 'coverage' ? (i) => v[i] >= 128 : (i) => v[i] > 0;
    }
    default: {
      const v = new Uint8Array(bytes);
      return (i) => v[i] !== 0;
    }
  }
}

export class Viewer {
  constructor(container) {
    this.container = container;
    // preserveDrawingBuffer: the picture can be read back (screenshots, tests).
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.setClearColor(0xfafbfd);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1e6);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(1, 2, 3);
    this.camera.add(sun);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.render());
    this.model = new THREE.Group();
    this.scene.add(this.model);
    this.boxes = new THREE.Group();
    this.scene.add(this.boxes);
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = this.container.clientWidth || 640, h = this.container.clientHeight || 480;
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() { this.renderer.render(this.scene, this.camera); }

  clear() {
    for (const group of [this.model, this.boxes]) {
      for (const o of group.children) o.geometry && o.geometry.dispose();
      group.clear();
    }
    this.render();
  }

  // The voxel surface, placed in model coordinates.
  showVoxels(grid, geometry) {
    this.clear();
    const material = new THREE.MeshLambertMaterial({ color: geometry.getAttribute('color') ? 0xffffff : 0x9aa7b8,
                                                     vertexColors: !!geometry.getAttribute('color') });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.scale.setScalar(grid.voxel_size);
    mesh.position.set(...grid.origin);
    this.model.add(mesh);
    this.frame(grid);
  }

  // An indexed surface in voxel units (sample (i, j, k) at i + 1/2, ...).
  showSurface(grid, { positions, indices }) {
    this.clear();
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(indices, 1));
    geometry.computeVertexNormals();
    const mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: 0x9aa7b8 }));
    mesh.scale.setScalar(grid.voxel_size);
    mesh.position.set(...grid.origin);
    this.model.add(mesh);
    this.frame(grid);
  }

  showMesh(grid, arrayBuffer) {
    this.clear();
    const geometry = new STLLoader().parse(arrayBuffer);
    geometry.computeVertexNormals();
    this.model.add(new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: 0x9aa7b8 })));
    this.frame(grid);
  }

  // A box in model coordinates (a region of the report), or none. The part
  // turns see-through meanwhile: a void or a thin region is inside it.
  showBox(min, max) {
    for (const o of this.boxes.children) o.geometry && o.geometry.dispose();
    this.boxes.clear();
    for (const o of this.model.children) {
      o.material.transparent = !!min;
      o.material.opacity = min ? 0.3 : 1;
      o.material.depthWrite = !min;
      o.material.needsUpdate = true;
    }
    if (min) {
      const box = new THREE.Box3(new THREE.Vector3(...min), new THREE.Vector3(...max));
      this.boxes.add(new THREE.Box3Helper(box, 0xe8590c));
    }
    this.render();
  }

  frame(grid) {
    const size = grid.dims.map((d) => d * grid.voxel_size);
    const centre = new THREE.Vector3(...grid.origin.map((o, a) => o + size[a] / 2));
    const radius = Math.hypot(...size) / 2 || 1;
    this.controls.target.copy(centre);
    this.camera.position.copy(centre).add(new THREE.Vector3(1.2, -1.6, 1.1).multiplyScalar(radius * 1.6));
    this.camera.up.set(0, 0, 1);
    this.camera.near = radius / 100;
    this.camera.far = radius * 100;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.render();
  }
}
