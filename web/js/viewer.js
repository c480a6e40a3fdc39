// The 3D view: the job's voxels as the surface between filled and empty
// voxels (in a colour job, each voxel in its colour), a distance field's
// zero level set (surface_nets.js), or a palette job's reconstruction,
// orbitable with the mouse (three.js). Regions of the report are shown as
// boxes. The part itself painted by wall thickness (wall_colours.js), with
// the reading under the cursor.
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

// The meshes of a glTF binary (the service's thickness glb: POSITION,
// NORMAL, the custom _THICKNESS, uint32 indices), in the file's own
// coordinates (the job's model units; the root node's turn to glTF's Y up
// is left out: the page keeps CAD's Z up).
export function readGlb(arrayBuffer) {
  const view = new DataView(arrayBuffer);
  if (view.getUint32(0, true) !== 0x46546c67) throw new Error('not a glTF binary');
  const jsonLength = view.getUint32(12, true);
  const gltf = JSON.parse(new TextDecoder().decode(new Uint8Array(arrayBuffer, 20, jsonLength)));
  if (!gltf.meshes) return null;  // an empty part
  const binStart = 20 + jsonLength + 8;
  const accessor = (i) => {
    const a = gltf.accessors[i], v = gltf.bufferViews[a.bufferView];
    const width = { SCALAR: 1, VEC3: 3, VEC4: 4 }[a.type];
    const Type = { 5126: Float32Array, 5125: Uint32Array }[a.componentType];
    return new Type(arrayBuffer, binStart + (v.byteOffset || 0) + (a.byteOffset || 0), a.count * width);
  };
  const p = gltf.meshes[0].primitives[0];
  return { positions: accessor(p.attributes.POSITION), normals: accessor(p.attributes.NORMAL),
           values: accessor(p.attributes._THICKNESS), indices: accessor(p.indices) };
}

// Where a reading crosses `level` on each triangle: segments, flat xyz.
export function isoLines(positions, values, indices, level) {
  const out = [];
  const at = (i, j) => {
    const t = (level - values[i]) / (values[j] - values[i]);
    for (let a = 0; a < 3; ++a) out.push(positions[3 * i + a] + t * (positions[3 * j + a] - positions[3 * i + a]));
  };
  for (let f = 0; f < indices.length; f += 3) {
    const v = [indices[f], indices[f + 1], indices[f + 2]];
    const crossing = [];
    for (let e = 0; e < 3; ++e) {
      const i = v[e], j = v[(e + 1) % 3];
      if (values[i] > 0 && values[j] > 0 && (values[i] < level) !== (values[j] < level)) crossing.push([i, j]);
    }
    if (crossing.length === 2) { at(...crossing[0]); at(...crossing[1]); }
  }
  return new Float32Array(out);
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
    // White light only: a painted part's hues are its legend's.
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x707070, 1.6));
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
    this.painted = null;  // the painted part's mesh and readings, for the cursor
    this.raycaster = new THREE.Raycaster();
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
      for (const o of group.children) {
        if (o.geometry) o.geometry.dispose();
        if (o.material?.map) o.material.map.dispose();
      }
      group.clear();
    }
    this.painted = null;
    this.render();
  }

  // The part's own mesh (readGlb) coloured by its readings through a lookup
  // (wall_colours.js lookupTexels), with dark lines where the readings cross
  // `marks` (the thin and thick bands' edges); framed on the part.
  showPainted(part, lookup, marks) {
    this.clear();
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(part.positions, 3));
    geometry.setAttribute('normal', new THREE.BufferAttribute(part.normals, 3));
    const uv = new Float32Array(2 * part.values.length);
    for (let i = 0; i < part.values.length; ++i) uv[2 * i] = Math.min(1, Math.max(0, part.values[i] / lookup.top));
    geometry.setAttribute('uv', new THREE.BufferAttribute(uv, 2));
    geometry.setIndex(new THREE.BufferAttribute(part.indices, 1));
    const texture = new THREE.DataTexture(lookup.rgba, lookup.texels, 1);
    texture.colorSpace = THREE.SRGBColorSpace;
    texture.magFilter = texture.minFilter = THREE.NearestFilter;
    texture.needsUpdate = true;
    const mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ map: texture }));
    this.model.add(mesh);
    for (const level of marks) {
      const lines = new THREE.BufferGeometry();
      lines.setAttribute('position', new THREE.BufferAttribute(isoLines(part.positions, part.values, part.indices, level), 3));
      this.model.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: 0x1d2330 })));
    }
    this.painted = { mesh, values: part.values };
    geometry.computeBoundingSphere();
    this.frameSphere(geometry.boundingSphere);
  }

  // The reading under a point of the canvas (client coordinates), or null.
  readingAt(clientX, clientY) {
    if (!this.painted) return null;
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2((clientX - r.left) / r.width * 2 - 1, -(clientY - r.top) / r.height * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    const hit = this.raycaster.intersectObject(this.painted.mesh)[0];
    if (!hit) return null;
    const { a, b, c } = hit.face, v = this.painted.values;
    const pos = this.painted.mesh.geometry.getAttribute('position');
    const corner = (i) => new THREE.Vector3().fromBufferAttribute(pos, i);
    const w = new THREE.Triangle(corner(a), corner(b), corner(c)).getBarycoord(hit.point, new THREE.Vector3());
    return { value: w.x * v[a] + w.y * v[b] + w.z * v[c], point: hit.point.toArray() };
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
    this.frameOn(mesh, grid);
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
    this.frameOn(mesh, grid);
  }

  showMesh(grid, arrayBuffer) {
    this.clear();
    const geometry = new STLLoader().parse(arrayBuffer);
    geometry.computeVertexNormals();
    const mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: 0x9aa7b8 }));
    this.model.add(mesh);
    this.frameOn(mesh, grid);
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
    this.frameSphere({ center: centre, radius: Math.hypot(...size) / 2 || 1 });
  }

  // Framed on what is drawn (a grid's margins left out); on the grid when
  // nothing is.
  frameOn(mesh, grid) {
    mesh.geometry.computeBoundingSphere();
    const s = mesh.geometry.boundingSphere;
    if (!(s.radius > 0)) return this.frame(grid);
    mesh.updateMatrixWorld();
    this.frameSphere({ center: s.center.clone().applyMatrix4(mesh.matrixWorld), radius: s.radius * mesh.scale.x });
  }

  // The camera at the distance where the sphere just fits the narrower of
  // the view's two angles, looking at it from above the front right.
  frameSphere({ center, radius }) {
    radius = radius || 1;
    const half = THREE.MathUtils.degToRad(this.camera.fov / 2);
    const narrower = Math.min(half, Math.atan(Math.tan(half) * this.camera.aspect));
    const distance = radius / Math.sin(narrower) * 1.05;
    const centre = new THREE.Vector3().copy(center);
    this.controls.target.copy(centre);
    this.camera.position.copy(centre).add(new THREE.Vector3(1.2, -1.6, 1.1).normalize().multiplyScalar(distance));
    this.camera.up.set(0, 0, 1);
    this.camera.near = radius / 100;
    this.camera.far = radius * 100;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.render();
  }
}
