// The analysis report as tables: mass properties (voxels against the exact
// mesh), parts, voids, wall thickness with its thin and thick regions.
// Clicking a region's row shows its box in the 3D view.

const fmt = (x, digits = 4) => (x === null || x === undefined ? '–' : Number(x).toPrecision(digits));
const vec = (v) => (v ? `(${v.map((x) => fmt(x)).join(', ')})` : '–');

function table(headings, rows, rowClass) {
  const t = document.createElement('table');
  const head = t.createTHead().insertRow();
  for (const h of headings) head.appendChild(Object.assign(document.createElement('th'), { textContent: h }));
  const body = t.createTBody();
  for (const r of rows) {
    const tr = body.insertRow();
    if (rowClass) tr.className = rowClass;
    for (const cell of r.cells) tr.insertCell().textContent = cell;
    if (r.onclick) tr.addEventListener('click', () => r.onclick(tr));
  }
  return t;
}

function heading(text) { return Object.assign(document.createElement('h3'), { textContent: text }); }

// Voids under a size hidden (a scan's or a coarse grid's specks of one or
// two voxels), the count of those shown said in the heading's place.
function voidFilter(container, voids) {
  const rows = [...container.querySelectorAll('table')].pop();
  if (!voids?.items?.length || !rows) return;
  const input = Object.assign(document.createElement('input'), { type: 'number', min: 0, step: 1, value: 0, id: 'void-min-voxels' });
  const shown = Object.assign(document.createElement('span'), { className: 'muted', id: 'voids-shown' });
  const label = Object.assign(document.createElement('label'), { textContent: 'hide voids under ' });
  label.append(input, ' voxels ');
  const apply = () => {
    const min = Number(input.value) || 0;
    let n = 0;
    [...rows.tBodies[0].rows].forEach((tr, i) => {
      tr.hidden = voids.items[i].voxels < min;
      if (!tr.hidden) ++n;
    });
    shown.textContent = `${n} of ${voids.items.length} listed shown; click one to see where it is`;
  };
  input.oninput = apply;
  apply();
  const p = document.createElement('p');
  p.append(label, shown);
  rows.before(p);
}

// Whether the uploaded mesh is closed, in words, from the job's mesh report.
function meshStatus(mesh) {
  if (!mesh) return null;
  if (mesh.watertight) return 'the mesh is watertight: closed, manifold and consistently oriented, so its exact volume holds';
  const parts = [];
  if (mesh.boundary_edges) parts.push(`${mesh.boundary_edges} open (boundary) edges`);
  if (mesh.nonmanifold_edges) parts.push(`${mesh.nonmanifold_edges} non-manifold edges`);
  if (mesh.inconsistent_edges) parts.push(`${mesh.inconsistent_edges} edges between triangles facing opposite ways`);
  return `the mesh is not watertight (${parts.join(', ') || 'no usable triangle'}): the voxels stand, the mesh's exact values may not`;
}

// `uploaded`: the job status's mesh report; `showRegion(min, max)` puts a
// box in the 3D view (null: none).
export function renderReport(container, report, uploaded, showRegion) {
  container.replaceChildren();
  const unit = report.unit || 'mm';
  const status = meshStatus(uploaded);
  if (status) {
    container.append(Object.assign(document.createElement('p'), {
      className: `mesh-status ${uploaded.watertight ? 'watertight' : 'open'}`, textContent: status,
    }));
  }
  const m = report.mass_properties;
  container.append(heading(`Mass properties (${unit})`));
  const mesh = m.mesh && m.mesh.available !== false ? m.mesh : null;
  container.append(table(['', 'voxels', 'mesh (exact)'], [
    { cells: ['volume', fmt(m.voxels.volume), fmt(mesh && mesh.volume)] },
    { cells: ['centroid', vec(m.voxels.centroid), vec(mesh && mesh.centroid)] },
    { cells: ['bounding box min', vec(m.voxels.bbox_min), vec(mesh && mesh.bbox_min)] },
    { cells: ['bounding box max', vec(m.voxels.bbox_max), vec(mesh && mesh.bbox_max)] },
    { cells: ['surface area', '–', fmt(mesh && mesh.surface_area)] },
  ]));
  if (m.mesh && m.mesh.available === false && m.mesh.reason) {
    container.append(Object.assign(document.createElement('p'), { className: 'muted mesh-reason', textContent: `mesh (exact): ${m.mesh.reason}` }));
  }
  if (m.difference) {
    container.append(Object.assign(document.createElement('p'), {
      className: 'muted',
      textContent: `voxel volume differs from the mesh's by ${(100 * m.difference.volume_relative).toFixed(3)} %`,
    }));
  }
  const clickable = (r) => (tr) => {
    const shown = tr.classList.contains('shown');
    for (const other of container.querySelectorAll('tr.shown')) other.classList.remove('shown');
    if (!shown) tr.classList.add('shown');
    showRegion(shown ? null : r.bbox_min, shown ? null : r.bbox_max);
  };
  const regions = (title, set, extra = () => [], extraHead = []) => {
    container.append(heading(`${title}: ${set.count}` + (set.total_volume !== undefined ? `, ${fmt(set.total_volume)} ${unit}³ in all` : '')));
    if (!set.items.length) return;
    container.append(table(['#', 'voxels', 'volume', 'centroid', 'box min', 'box max', ...extraHead],
      set.items.map((r, i) => ({ cells: [i + 1, r.voxels, fmt(r.volume), vec(r.centroid), vec(r.bbox_min), vec(r.bbox_max), ...extra(r)],
                                 onclick: clickable(r) })), 'region'));
  };
  regions('Parts', report.parts);
  regions('Voids', report.voids);
  voidFilter(container, report.voids);
  const t = report.thickness;
  if (t) {
    container.append(heading(`Wall thickness (${unit})`));
    const verdict = document.createElement('p');
    verdict.innerHTML = `min ${fmt(t.min)}, mean ${fmt(t.mean)}, max ${fmt(t.max)}; ` +
      `min wall ${fmt(t.min_wall)}, max wall ${fmt(t.max_wall)}: `;
    verdict.append(Object.assign(document.createElement('strong'), {
      className: `verdict ${t.verdict || ''}`, textContent: t.verdict || 'no limits given',
    }));
    if (t.verdict_reason) {
      verdict.append(Object.assign(document.createElement('span'), { className: 'verdict-reason', textContent: ` (${t.verdict_reason})` }));
    }
    container.append(verdict, Object.assign(document.createElement('p'), { className: 'muted', textContent: t.error_bound }));
    if (t.voxel_size_to_decide) {
      container.append(Object.assign(document.createElement('p'), {
        className: 'decide', textContent: `voxel size to decide: ${fmt(t.voxel_size_to_decide)} ${unit} or smaller`,
      }));
    }
    // Certain: beyond the limit by more than the error bound; else marginal.
    const certainty = (r) => (r.certain === undefined ? [] : [r.certain ? 'certain' : 'marginal']);
    const thin = (r) => [fmt(r.min_thickness ?? r.max_thickness), fmt(r.mean_thickness), ...certainty(r)];
    const thick = (r) => [fmt(r.max_thickness ?? r.min_thickness), fmt(r.mean_thickness), ...certainty(r)];
    // Reports kept by earlier releases have no certainty.
    const sure = 'verdict_reason' in t ? ['beyond the bound'] : [];
    regions('Thin regions', t.thin_regions, thin, ['thinnest', 'mean', ...sure]);
    regions('Thick regions', t.thick_regions, thick, ['thickest', 'mean', ...sure]);
    if (t.near_min_wall?.count) regions('Within a voxel over min wall', t.near_min_wall, thin, ['thinnest', 'mean', 'beyond the bound']);
    if (t.near_max_wall?.count) regions('Within a voxel under max wall', t.near_max_wall, thick, ['thickest', 'mean', 'beyond the bound']);
  }
}
