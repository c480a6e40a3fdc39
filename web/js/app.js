// voxd's page: submit a mesh with a job, follow it over its event stream,
// look at what it made. Plain ES modules over the public API, so it is also
// an example of using it (docs/web.md).
import { ApiError, apiKey, call, getJson, listJobs, removeJob, submitJob, watchJob } from './api.js';
import { RadiographyView } from './radiography.js';
import { renderReport } from './report.js';
import { enclosedVolume, surfaceNets } from './surface_nets.js';
import { MAX_VIEW_VOXELS, Viewer, filledTest, readGlb, voxelSurface } from './viewer.js';
import { bandOf, fmt, lookupTexels, renderLegend, wallBands } from './wall_colours.js';

const $ = (id) => document.getElementById(id);
let schema = null;       // proto-schemas/job-params.schema.json
let meshFile = null;
const meshesSent = new Map();  // job id -> the mesh file this page sent for it
let current = null;      // the job shown
let stopWatching = () => {};
let viewer = null;
const radiography = new RadiographyView({
  canvas: $('rad-canvas'), readout: $('rad-readout'), scale: $('rad-scale'), lo: $('rad-lo'), hi: $('rad-hi'),
});

// ---- problems ---------------------------------------------------------------

function showProblem(e) {
  let title = e instanceof ApiError ? e.title : 'Something went wrong';
  let detail = e instanceof ApiError ? e.detail : String(e.message || e);
  // The API's words are for programs; a person at the page is told where
  // the key goes.
  if (e instanceof ApiError && e.status === 401) {
    title = apiKey.get() ? 'This API key is not accepted' : 'This service needs an API key';
    detail = apiKey.get() ? 'check the key in the API key box at the top right, or ask the service\'s operator for one'
                          : 'enter your key in the API key box at the top right (it stays in this browser); ask the service\'s operator for one';
  }
  $('problem-title').textContent = title;
  $('problem-detail').textContent = detail;
  $('problem').hidden = false;
}
const guarded = (fn) => async (...args) => {
  try { await fn(...args); } catch (e) { showProblem(e); }
};
$('problem-close').onclick = () => { $('problem').hidden = true; };

// ---- the job form, from the schema's enums, limits and defaults --------------

function fillSelect(select, values, chosen) {
  select.replaceChildren(...values.map((v) => new Option(v, v, false, v === chosen)));
}

// The kind of input the form renders for an option, or null for one it
// cannot give: enums, numbers, booleans; a number or a word ("band": 3 or
// "full"); a colour, a list of colours, a ramp of colour stops; a lookup
// image, uploaded.
function inputKind(spec) {
  const s = spec.$ref ? resolve(spec.$ref) : spec;
  if (spec.$ref === '#/$defs/rgba') return 'rgba';
  if (s.enum && s.enum.every((v) => typeof v === 'string')) return 'enum';
  if (['boolean', 'integer', 'number'].includes(s.type)) return s.type;
  if (s.oneOf && s.oneOf.length === 2 && s.oneOf.some((o) => o.type === 'number') && s.oneOf.some((o) => typeof o.const === 'string'))
    return 'number-or-word';
  if (s.type === 'array' && s.items?.$ref === '#/$defs/rgba' && Array.isArray(s.default)) return 'rgba-list';
  if (s.type === 'array' && s.items?.properties?.position && s.items?.properties?.color && Array.isArray(s.default)) return 'ramp';
  if (s.type === 'object' && s.properties?.dims && s.properties?.colors) return 'lookup-image';
  return null;
}

// The values of enum option `name` the form cannot submit: those the
// options' allOf rules say need an option the form has no input for.
function unofferable(options, name) {
  const out = new Set();
  for (const rule of options.allOf || []) {
    const value = rule.if?.properties?.[name]?.const;
    const needs = rule.then?.required || [];
    if (value !== undefined && needs.some((n) => !options.properties[n] || !inputKind(options.properties[n]))) out.add(value);
  }
  return out;
}

// The values of another option (the slice's function) an option applies to,
// from the allOf rules "if it is given, then function is one of ...": null
// when it applies whatever they are.
function appliesTo(options, name) {
  for (const rule of options.allOf || []) {
    const given = rule.if?.required || (rule.if?.anyOf || []).flatMap((a) => a.required || []);
    if (!given.includes(name)) continue;
    for (const [other, limit] of Object.entries(rule.then?.properties || {})) {
      const values = limit.const !== undefined ? [limit.const] : limit.enum;
      if (values) return { option: other, values };
    }
  }
  return null;
}

const hex = (rgba) => (typeof rgba === 'string' ? rgba.slice(0, 7)
  : `#${rgba.slice(0, 3).map((c) => c.toString(16).padStart(2, '0')).join('')}`);
const rgbaOf = (hexColour) => [1, 3, 5].map((i) => parseInt(hexColour.slice(i, i + 2), 16)).concat(255);
const colourInput = (value) => Object.assign(document.createElement('input'), { type: 'color', value: hex(value) });

// A lookup image as the API takes it: cells along x and y (one layer in z),
// each pixel's colour, x fastest; alpha dropped (0 would mean empty).
async function lookupFromImage(file) {
  const bitmap = await createImageBitmap(file);
  if (bitmap.width > 64 || bitmap.height > 64)
    throw new ApiError(0, { title: 'Lookup image too large', detail: `${bitmap.width} × ${bitmap.height} pixels: a lookup is at most 64 cells a side` });
  const canvas = Object.assign(document.createElement('canvas'), { width: bitmap.width, height: bitmap.height });
  const ctx = canvas.getContext('2d');
  ctx.drawImage(bitmap, 0, 0);
  const px = ctx.getImageData(0, 0, bitmap.width, bitmap.height).data;
  const colors = [];
  // Image rows run top down; the lookup's y runs up.
  for (let y = bitmap.height - 1; y >= 0; --y)
    for (let x = 0; x < bitmap.width; ++x) colors.push([...px.slice(4 * (y * bitmap.width + x), 4 * (y * bitmap.width + x) + 3), 255]);
  return { dims: [bitmap.width, bitmap.height, 1], colors };
}

// One input (or a row of them) for an option, by its kind.
function optionInput(name, s, kind, options) {
  let input;
  switch (kind) {
    case 'enum': {
      input = document.createElement('select');
      const skip = unofferable(options, name);
      fillSelect(input, s.enum.filter((v) => !skip.has(v)), s.default);
      return input;
    }
    case 'boolean': return Object.assign(document.createElement('input'), { type: 'checkbox', checked: !!s.default });
    case 'integer':
    case 'number':
      input = Object.assign(document.createElement('input'), { type: 'number', step: kind === 'integer' ? 1 : 'any' });
      if (s.minimum !== undefined) input.min = s.minimum;
      if (s.maximum !== undefined) input.max = s.maximum;
      if (s.default !== undefined) input.placeholder = s.default;
      return input;
    case 'number-or-word': {
      const word = s.oneOf.find((o) => typeof o.const === 'string').const;
      return Object.assign(document.createElement('input'), { type: 'text', placeholder: `${s.default ?? ''} or ${word}`, size: 8 });
    }
    case 'rgba': return colourInput(s.default ?? [200, 200, 200]);
    case 'rgba-list':
    case 'ramp': {
      input = Object.assign(document.createElement('span'), { className: 'colours' });
      for (const item of s.default) {
        const c = colourInput(kind === 'ramp' ? item.color : item);
        if (kind === 'ramp') c.dataset.position = item.position;
        input.append(c);
      }
      return input;
    }
    case 'lookup-image': {
      input = Object.assign(document.createElement('input'), { type: 'file', accept: 'image/png,image/gif,image/bmp' });
      input.onchange = guarded(async () => {
        input.lookup = input.files[0] ? await lookupFromImage(input.files[0]) : undefined;
      });
      return input;
    }
    default: return null;
  }
}

// One input per option of a mode the form can give, each shown only while
// the option applies (a slice's colours with their function), into `box`.
function optionInputs(modeName, box = $('mode-options')) {
  box.replaceChildren();
  const options = schema.properties[modeName];
  if (!options || !options.properties) return;
  for (const [name, spec] of Object.entries(options.properties)) {
    const s = spec.$ref ? resolve(spec.$ref) : spec;
    const kind = inputKind(spec);
    const input = kind && optionInput(name, { ...s, default: spec.default ?? s.default }, kind, options);
    if (!input) continue;
    input.dataset.option = name;
    input.dataset.kind = kind;
    input.title = spec.description || s.description || '';
    const label = Object.assign(document.createElement('label'), { textContent: `${name} ` });
    const applies = appliesTo(options, name);
    if (applies) {
      label.dataset.when = applies.option;
      label.dataset.values = JSON.stringify(applies.values);
    }
    label.append(input);
    box.append(label);
  }
  const showApplying = () => {
    for (const label of box.querySelectorAll('label[data-when]')) {
      const chosen = box.querySelector(`[data-option="${label.dataset.when}"]`)?.value;
      label.hidden = !JSON.parse(label.dataset.values).includes(chosen);
    }
  };
  box.onchange = showApplying;
  showApplying();
}

// The options given in `box` (those shown), as the job JSON takes them.
function optionsFrom(box) {
  const options = {};
  for (const input of box.querySelectorAll(':scope > label:not([hidden]) > [data-option]')) {
    const value = optionValue(input);
    if (value !== undefined) options[input.dataset.option] = value;
  }
  return options;
}

// An option's value from its input, or undefined to leave it out.
function optionValue(input) {
  switch (input.dataset.kind) {
    case 'boolean': return input.checked;
    case 'enum': return input.value;
    case 'integer':
    case 'number': return input.value === '' ? undefined : Number(input.value);
    case 'number-or-word': {
      const v = input.value.trim();
      return v === '' ? undefined : Number.isFinite(Number(v)) ? Number(v) : v;
    }
    case 'rgba': return rgbaOf(input.value);
    case 'rgba-list': return [...input.querySelectorAll('input')].map((c) => rgbaOf(c.value));
    case 'ramp': return [...input.querySelectorAll('input')].map((c) => ({ position: Number(c.dataset.position), color: rgbaOf(c.value) }));
    case 'lookup-image': return input.lookup;
    default: return undefined;
  }
}

// The modes the schema says take no inside test (coverage, palette: they
// count crossings themselves), read from its allOf rules
// ("mode is M" -> "not required inside"), so the form never offers one.
function modesWithoutInside() {
  const out = new Set();
  for (const rule of schema.allOf || []) {
    const mode = rule.if?.properties?.mode?.const;
    if (mode && rule.then?.not?.required?.includes('inside')) out.add(mode);
  }
  return out;
}

// The modes the schema refuses "device": "cuda" for: their work runs only
// on the CPU, so the form offers them no device.
function modesOnTheCpuOnly() {
  for (const rule of schema.allOf || []) {
    const modes = rule.if?.properties?.mode?.enum;
    if (modes && rule.then?.properties?.device) return new Set(modes);
  }
  return new Set();
}

function showDevice(modeName) {
  const takes = !modesOnTheCpuOnly().has(modeName);
  $('device').disabled = !takes;
  $('device').closest('label').hidden = !takes;
}

function showInside(modeName) {
  const takes = !modesWithoutInside().has(modeName);
  $('inside').disabled = !takes;
  $('inside').closest('label').hidden = !takes;
}

function resolve(ref) {
  return ref.replace(/^#\//, '').split('/').reduce((o, k) => o[k], schema);
}

async function loadSchema() {
  schema = await getJson('/ui/job-params.schema.json');
  const p = schema.properties;
  fillSelect($('mode'), p.mode.enum, p.mode.default);
  fillSelect($('inside'), p.inside.enum, p.inside.default);
  fillSelect($('units'), p.units.enum, p.units.default);
  // Unset, the job takes the service's own device (voxd serve --device).
  $('device').replaceChildren(new Option('service default', ''), ...p.device.enum.map((d) => new Option(d, d)));
  const byResolution = p.grid.oneOf.find((g) => g.required.includes('resolution')).properties.resolution;
  Object.assign($('resolution'), { min: byResolution.minimum, max: Math.min(byResolution.maximum, 4096), value: 128 });
  $('mode').onchange = () => {
    optionInputs($('mode').value);
    showInside($('mode').value);
    showDevice($('mode').value);
  };
  optionInputs($('mode').value);
  showInside($('mode').value);
  showDevice($('mode').value);
}

function jobParams() {
  const params = { mode: $('mode').value, units: $('units').value };
  if (!modesWithoutInside().has(params.mode)) params.inside = $('inside').value;
  if (!$('device').disabled && $('device').value) params.device = $('device').value;
  const kind = document.querySelector('input[name=grid-kind]:checked').value;
  params.grid = kind === 'resolution' ? { resolution: Number($('resolution').value) }
                                      : { voxel_size: Number($('voxel-size').value) };
  if (schema.properties[params.mode]?.properties) params[params.mode] = optionsFrom($('mode-options'));
  params.analyses = [];
  if ($('want-report').checked) {
    const a = { kind: 'analysis' };
    if ($('min-wall').value) a.min_wall = Number($('min-wall').value);
    if ($('max-wall').value) a.max_wall = Number($('max-wall').value);
    params.analyses.push(a);
  }
  if ($('want-radiography').checked)
    params.analyses.push({ kind: 'radiography', axis: 'z', measure: 'max', format: 'png16', unit: 'model' });
  return params;
}

function chooseFile(file) {
  meshFile = file;
  $('mesh-name').textContent = file ? `${file.name} (${(file.size / 1024).toFixed(1)} KiB)` : 'no file chosen';
}
$('mesh-file').onchange = (e) => chooseFile(e.target.files[0]);
const drop = $('drop');
drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
drop.addEventListener('dragleave', () => drop.classList.remove('over'));
drop.addEventListener('drop', (e) => {
  e.preventDefault();
  drop.classList.remove('over');
  if (e.dataTransfer.files.length) chooseFile(e.dataTransfer.files[0]);
});

$('job-form').onsubmit = guarded(async (e) => {
  e.preventDefault();
  if (!meshFile) throw new ApiError(0, { title: 'No mesh', detail: 'drop a mesh file or pick one first' });
  $('problem').hidden = true;
  $('submit').disabled = true;
  try {
    const job = await submitJob(meshFile, jobParams());
    meshesSent.set(job.id, meshFile);
    openJob(job.id);
    refreshJobs();
  } finally {
    $('submit').disabled = false;
  }
});

// ---- recent jobs ------------------------------------------------------------

// The list is drawn again only when a job in it changed, and keeps its
// scroll position (a refresh every 5 s used to jump it back to the top).
let shownJobs = '';
const refreshJobs = guarded(async () => {
  const { jobs } = await listJobs();
  const key = JSON.stringify(jobs.map((j) => [j.id, j.state, j.name]));
  if (key === shownJobs) return;
  shownJobs = key;
  const list = $('jobs');
  const top = list.scrollTop;
  const defaultMode = schema?.properties?.mode?.default ?? 'solid';
  list.replaceChildren(...jobs.map((j) => {
    const li = document.createElement('li');
    li.dataset.id = j.id;
    li.title = j.id;
    li.append(Object.assign(document.createElement('span'), { className: `state ${j.state}`, textContent: j.state }),
              Object.assign(document.createElement('span'), { className: 'job-name', textContent: j.name || j.id.slice(0, 8) }),
              ` ${j.params.mode ?? defaultMode} ${j.grid.dims.join('×')} `,
              Object.assign(document.createElement('span'), { className: 'muted', textContent: j.created_at.slice(11, 19) }));
    li.onclick = () => openJob(j.id);
    return li;
  }));
  list.scrollTop = top;
});

// ---- one job: progress over its event stream --------------------------------

function showProgress(state, progress, stage) {
  $('job-state').textContent = state;
  $('job-state').className = `state ${state}`;
  $('progress-bar').style.width = `${Math.round(progress * 100)}%`;
  $('progress-text').textContent = `${Math.round(progress * 100)} %` + (stage ? ` · ${stage}` : '');
  $('cancel').disabled = !(state === 'queued' || state === 'running');
}

// The job JSON's analyses that are done, as the stream tells of them (those
// done before it was opened come with its first event).
let analysesDone = new Map();
function noteAnalyses(entries) {
  (entries || []).forEach((a, i) => {
    if (a.state === 'ready' || a.state === 'failed') analysesDone.set(a.index ?? i, `${a.request.kind} ${a.state}`);
  });
  $('analyses-ready').textContent = [...analysesDone.keys()].sort((x, y) => x - y)
    .map((k) => `${analysesDone.get(k)} · `).join('');
}

// The inside test the job's solid is made with and why, and what the user
// should know about the result (the job status's warnings), from the
// status the job was accepted with onwards.
function showJobNotes(job) {
  const inside = job.inside;
  $('job-inside').textContent = !inside ? ''
    : `inside test: ${inside.test}` + (inside.chosen === 'auto' ? `, chosen from the mesh: ${inside.reason}`
                                                              : inside.reason ? ` (${inside.reason})` : ', as asked');
  // Where a GPU could have done the work: where it was done.
  $('job-device').textContent = job.values?.device ? `computed on: ${job.values.device}` : '';
  $('job-warnings').replaceChildren(...(job.warnings || []).map((w) => {
    const li = Object.assign(document.createElement('li'), { className: 'warning', textContent: w.message });
    li.dataset.code = w.code;
    return li;
  }));
}

function openJob(id) {
  stopWatching();
  current = { id, job: null };
  $('job-panel').hidden = false;
  $('results').hidden = true;
  $('job-id').textContent = id;
  // Nothing of the job shown before stays: its 3D view's words and legend.
  $('view-info').textContent = '';
  $('view-readout').textContent = '';
  $('wall-legend').hidden = true;
  analysesDone = new Map();
  $('analyses-ready').textContent = '';
  showJobNotes({});
  showProgress('queued', 0, null);
  const mine = current;
  stopWatching = watchJob(id, {
    job: (job) => {
      mine.job = job;
      noteAnalyses(job.analyses);
      showJobNotes(job);
      showProgress(job.state, job.progress, job.stage);
    },
    state: (s) => showProgress(s.state, s.progress, s.stage),
    progress: (p) => showProgress('running', p.progress, p.stage),
    analysis: (a) => noteAnalyses([a]),
    end: guarded(async (job) => {
      mine.job = job;
      noteAnalyses(job.analyses);
      showJobNotes(job);
      showProgress(job.state, job.progress, null);
      refreshJobs();
      if (current !== mine) return;
      if (job.state === 'failed' && job.error) showProblem(new ApiError(job.error.status, job.error));
      if (job.state === 'succeeded') await showResults(job);
    }),
    gone: () => { showProgress('deleted', 0, null); refreshJobs(); },
    error: () => showProblem(new ApiError(0, { title: 'Event stream lost', detail: 'the connection to the service closed; reload the job' })),
  });
}

$('cancel').onclick = guarded(async () => { await removeJob(current.id); });
$('delete').onclick = guarded(async () => {
  await removeJob(current.id);
  stopWatching();
  $('job-panel').hidden = true;
  refreshJobs();
});

// ---- results ------------------------------------------------------------------

function selectTab(name) {
  for (const b of $('tabs').querySelectorAll('button')) b.classList.toggle('active', b.dataset.tab === name);
  for (const tab of document.querySelectorAll('.tab')) tab.hidden = tab.id !== `tab-${name}`;
  if (name === 'view3d' && viewer) viewer.resize();
}
for (const b of $('tabs').querySelectorAll('button')) b.onclick = () => selectTab(b.dataset.tab);

// The analysis the job asked for (its min and max wall), else one with none.
function reportRequest(job) {
  return (job.analyses || []).find((a) => a.request && a.request.kind === 'analysis');
}
// The job's report, fetched once for the report tab and the painted part.
function reportOf(job) {
  if (current?.job !== job) return getJson(reportRequest(job)?.url ?? `/v1/jobs/${job.id}/analysis`);
  current.report ??= getJson(reportRequest(job)?.url ?? `/v1/jobs/${job.id}/analysis`);
  return current.report;
}

// The colourings a job's sections and previews can take: wall thickness
// for a solid's bits, distance for an sdf's values, else none.
// An sdf's sections open coloured by distance, with their legend (its
// plain section is a grey ramp with none).
function offerColours(mode) {
  const colours = { solid: ['none', 'thickness'], surface: ['none', 'thickness'], 'solid+surface': ['none', 'thickness'],
                    sdf: ['none', 'distance'] }[mode] || ['none'];
  for (const id of ['sec-colour', 'prev-colour']) {
    const keep = colours.includes($(id).value) && $(id).value !== 'none' ? $(id).value : null;
    fillSelect($(id), colours, keep ?? (id === 'sec-colour' && mode === 'sdf' ? 'distance' : 'none'));
  }
}

async function showResults(job) {
  $('results').hidden = false;
  const mode = job.params.mode ?? schema?.properties?.mode?.default ?? 'solid';
  offerColours(mode);
  // A solid job's part painted by wall thickness: first when the job asked
  // for the report (its thickness is made already), else on request.
  const solid = reportRequest(job) ? ['wall thickness', 'voxels'] : ['voxels', 'wall thickness'];
  const sources = { palette: ['voxels', 'reconstruction'], sdf: ['zero level set', 'voxels'], solid }[mode] || ['voxels'];
  fillSelect($('view-source'), sources, sources[0]);
  $('view-source').onchange = guarded(() => show3d(job));
  sliceEditor.open(job, mode);
  await Promise.all([show3d(job), showRadiography(job), showSection(job, true), showPreviews(job), showReport(job)]
    .map((p) => p.catch(showProblem)));
  showDownloads(job);
}

// The part's own mesh painted by its wall thickness, a legend in the
// report's unit with the job's limits, the reading under the cursor.
async function showPainted(job) {
  const asked = reportRequest(job)?.request || {};
  const query = new URLSearchParams({ format: 'glb', unit: 'model' });
  if (asked.min_wall) query.set('min_wall', asked.min_wall);
  if (asked.max_wall) query.set('max_wall', asked.max_wall);
  const [report, res] = await Promise.all([reportOf(job), call(`/v1/jobs/${job.id}/thickness?${query}`)]);
  const part = readGlb(await res.arrayBuffer());
  const t = report.thickness;
  if (!part || !t) {
    viewer.clear();
    $('view-info').textContent = 'no wall to paint: the part has no filled voxel';
    return;
  }
  const bands = wallBands(t);
  // Lines where a band of note begins or ends: the thin, marginal and thick edges.
  const marks = [];
  for (let i = 1; i < bands.length; ++i) if (bands[i].kind !== bands[i - 1].kind) marks.push(bands[i].lo);
  viewer.showPainted(part, lookupTexels(bands), marks);
  renderLegend($('wall-legend'), bands, report.unit);
  $('wall-legend').hidden = false;
  const limits = [t.min_wall && `min wall ${fmt(t.min_wall)}`, t.max_wall && `max wall ${fmt(t.max_wall)}`].filter(Boolean);
  $('view-info').textContent = `wall thickness on the part (${part.indices.length / 3} triangles), ${report.unit}` +
    (limits.length ? `; ${limits.join(', ')} ± the error bound` : '; no limits given');
  const canvas = $('viewer').querySelector('canvas');
  canvas.onpointermove = (e) => {
    const r = viewer.readingAt(e.clientX, e.clientY);
    const band = r && bandOf(bands, r.value);
    $('view-readout').textContent = !r ? '' : !band ? 'no reading here'
      : `wall ${fmt(r.value)} ${report.unit}` + (band.kind === 'within' ? '' : ` · ${band.kind}`);
    $('view-readout').dataset.value = r ? r.value : '';
  };
}

async function show3d(job) {
  if (!viewer) viewer = new Viewer($('viewer'));
  const grid = job.grid;
  $('wall-legend').hidden = true;
  $('view-readout').textContent = '';
  $('viewer').querySelector('canvas').onpointermove = null;
  if ($('view-source').value === 'wall thickness') return showPainted(job);
  if (grid.voxel_count > MAX_VIEW_VOXELS) {
    viewer.clear();
    $('view-info').textContent = `${grid.voxel_count} voxels: too many to draw here; see the previews`;
    return;
  }
  if ($('view-source').value === 'reconstruction') {
    const res = await call(`/v1/jobs/${job.id}/volume?format=stl`);
    viewer.showMesh(grid, await res.arrayBuffer());
    $('view-info').textContent = 'palette reconstruction';
    return;
  }
  const res = await call(`/v1/jobs/${job.id}/volume?format=raw`);
  const type = res.headers.get('X-Voxd-Value-Type') || 'bit';
  const bytes = await res.arrayBuffer();
  if ($('view-source').value === 'zero level set') {
    const [nx, ny] = grid.dims, d = new Float32Array(bytes);
    // Positive outside; beyond the grid, half a voxel out (a fitted grid's
    // part reaches its outermost voxels).
    const sign = job.values.sign_convention === 'inside_positive' ? -1 : 1;
    const half = job.values.unit === 'voxels' ? 0.5 : grid.voxel_size / 2;
    const surface = surfaceNets(grid.dims, (i, j, k) => sign * d[i + nx * (j + ny * k)], half);
    viewer.showSurface(grid, surface);
    const volume = enclosedVolume(surface) * grid.voxel_size ** 3;
    $('view-info').textContent =
      `zero level set: ${surface.indices.length / 3} triangles (surface nets), enclosing ${volume.toPrecision(5)} units³`;
    return;
  }
  const filled = filledTest(bytes, type, job.params.mode);
  let colourOf = null;
  if (type === 'rgba8') {
    const v = new Uint8Array(bytes);
    colourOf = (i) => [v[4 * i] / 255, v[4 * i + 1] / 255, v[4 * i + 2] / 255];
  }
  viewer.showVoxels(grid, voxelSurface(grid.dims, filled, colourOf));
  $('view-info').textContent = `${job.filled_voxels} filled voxels of ${grid.dims.join(' × ')}, ${grid.voxel_size.toPrecision(4)} each`;
}

async function showRadiography(job) {
  await radiography.show(job.id, $('rad-axis').value, $('rad-measure').value);
}
$('rad-axis').onchange = $('rad-measure').onchange = guarded(() => current?.job && showRadiography(current.job));

async function showSection(job, reset) {
  const axis = $('sec-axis').value, a = 'xyz'.indexOf(axis);
  const slider = $('sec-index');
  slider.max = job.grid.dims[a] - 1;
  if (reset) slider.value = Math.floor(job.grid.dims[a] / 2);
  const index = Number(slider.value);
  const at = job.grid.origin[a] + (index + 0.5) * job.grid.voxel_size;
  $('sec-where').textContent = `layer ${index} of ${job.grid.dims[a]}, ${axis} = ${at.toPrecision(5)}`;
  const res = await call(`/v1/jobs/${job.id}/section?axis=${axis}&index=${index}&colour=${$('sec-colour').value}`);
  const img = $('sec-image');
  if (img.src) URL.revokeObjectURL(img.src);
  img.src = URL.createObjectURL(await res.blob());
}
$('sec-axis').onchange = guarded(() => current?.job && showSection(current.job, true));
$('sec-index').oninput = guarded(() => current?.job && showSection(current.job, false));
$('sec-colour').onchange = guarded(() => current?.job && showSection(current.job, false));

async function showPreviews(job) {
  const colour = $('prev-colour').value;
  $('previews').replaceChildren(...['+x', '-x', '+y', '-y', '+z', '-z'].map((view) => {
    const figure = document.createElement('figure');
    const img = Object.assign(document.createElement('img'), { alt: `preview from ${view}`, loading: 'lazy' });
    call(`/v1/jobs/${job.id}/preview?view=${encodeURIComponent(view)}&colour=${colour}`)
      .then((r) => r.blob()).then((b) => { img.src = URL.createObjectURL(b); }).catch(showProblem);
    figure.append(img, Object.assign(document.createElement('figcaption'), { textContent: `from ${view}` }));
    return figure;
  }));
}
$('prev-colour').onchange = guarded(() => current?.job && showPreviews(current.job));

// ---- a slice function on the part, edited live (Liao) ---------------------------
// The finished job's solid coloured by a slice function a layer and a view
// at a time (colour=slice) while its options change: one update in flight,
// the latest options next, so dragging never queues stale pictures. The
// coloured volume itself is a slice job of the same mesh and grid, made
// when asked.

const sliceEditor = (() => {
  let job = null;
  const urls = {};
  const timing = $('slice-timing');

  // The axis as the frame's direction; the options the form gives.
  const options = () => ({ ...optionsFrom($('slice-options')),
                           axis: { x: [1, 0, 0], y: [0, 1, 0], z: [0, 0, 1] }[$('slice-frame-axis').value] });

  // Lengths start in proportion to the part (the schema's defaults suit a
  // part of a few units), and each number but the seed gets a slider: a
  // length up to half the part's size, an octave count over its range,
  // turbulence up to 4.
  const lengths = { noise_scale: 1 / 8, period: 1 / 6, checker_size: 1 / 8 };
  function addSliders() {
    const extent = Math.max(...job.grid.dims) * job.grid.voxel_size;
    for (const number of $('slice-options').querySelectorAll('input[type=number]')) {
      const name = number.dataset.option;
      if (lengths[name]) number.value = Number((extent * lengths[name]).toPrecision(3));
      const integer = number.dataset.kind === 'integer';
      if (integer && !(number.max !== '' && Number.isFinite(Number(number.max)))) continue;  // the seed
      const max = integer ? Number(number.max) : name === 'turbulence' ? 4 : extent / 2;
      const step = integer ? 1 : max / 500;
      const min = integer ? Number(number.min) : name === 'turbulence' ? 0 : step;  // lengths are > 0
      const range = Object.assign(document.createElement('input'), { type: 'range', min, max, step, className: 'drag' });
      range.dataset.drags = number.dataset.option;
      range.value = number.value || number.placeholder;
      // The form's own input listener (below) makes the update.
      range.oninput = () => { number.value = range.value; };
      number.addEventListener('input', () => { range.value = number.value; });
      number.after(range);
    }
  }

  // One picture for `slice` (the options' JSON, URL-encoded); the <img>
  // keeps which options it shows.
  async function image(kind, query, slice) {
    const res = await call(`/v1/jobs/${job.id}/${kind}?${query}&colour=slice&slice=${slice}`);
    const url = URL.createObjectURL(await res.blob());
    const img = $(`slice-${kind}`);
    await new Promise((resolve, reject) => { img.onload = resolve; img.onerror = reject; img.src = url; });
    img.dataset.slice = slice;
    if (urls[kind]) URL.revokeObjectURL(urls[kind]);
    urls[kind] = url;
  }

  // Each picture on its own loop: one request in flight, the latest
  // options next, once, so dragging never queues stale pictures and the
  // section is not held up by the view. A picture already shown for the
  // same job, query and options is not asked for again: a drag step can
  // reach here more than once (input, then change on release), and a slow
  // service must not be sent each step twice.
  function loop(kind, query, counter, settled = () => {}) {
    let busy = false, again = false, shown = null;
    async function run() {
      if (!job) return;
      // custom needs its lookup image first.
      if (options().function === 'custom' && !options().lookup) {
        counter.textContent = 'upload a lookup image';
        return;
      }
      if (busy) { again = true; return; }
      busy = true;
      try {
        do {
          again = false;
          const q = query(), slice = encodeURIComponent(JSON.stringify(options()));
          const key = `${job.id}?${q}&${slice}`;
          if (key === shown) continue;
          const started = performance.now();
          await image(kind, q, slice);
          shown = key;
          const ms = performance.now() - started;
          counter.dataset.updates = String(Number(counter.dataset.updates || 0) + 1);
          counter.dataset.lastMs = ms.toFixed(1);
          counter.textContent = `${kind} updated in ${ms.toFixed(0)} ms`;
        } while (again);
        settled();
      } catch (e) {
        showProblem(e);
      } finally {
        busy = false;
      }
    }
    return run;
  }
  // The view follows once the section has caught up with the options: while
  // a parameter is dragged the section has the service's cores to itself.
  const preview = loop('preview', () => `view=${encodeURIComponent($('slice-view').value)}`, $('slice-view-timing'));
  const section = loop('section', () => {
    const axis = $('slice-axis').value, slider = $('slice-index');
    slider.max = job.grid.dims['xyz'.indexOf(axis)] - 1;
    return `axis=${axis}&index=${slider.value}`;
  }, timing, preview);
  // After the event's other handlers (the form's own shows the options
  // that apply first).
  const update = () => queueMicrotask(section);

  $('slice-options').addEventListener('input', update);
  $('slice-options').addEventListener('change', update);
  for (const id of ['slice-axis', 'slice-index', 'slice-view', 'slice-frame-axis']) $(id).addEventListener('input', update);

  $('slice-make').onclick = guarded(async () => {
    const file = meshesSent.get(job.id);
    if (!file) throw new ApiError(0, { title: 'No mesh here', detail: 'this page did not send this job\'s mesh: drop the mesh and submit a slice job with these options' });
    const params = { ...job.params, mode: 'slice', slice: options(), analyses: [] };
    const made = await submitJob(file, params);
    meshesSent.set(made.id, file);
    $('slice-made').textContent = `slice job ${made.id}`;
    $('slice-made').dataset.job = made.id;
    openJob(made.id);
    refreshJobs();
  });

  return {
    open(finished, mode) {
      // A job whose voxels are a solid (solid jobs, and slice jobs to try
      // other functions) kept its mesh for the frame.
      const offered = ['solid', 'solid+surface', 'slice'].includes(mode);
      $('slice-tab').hidden = !offered;
      job = offered ? finished : null;
      if (!offered) return;
      optionInputs('slice', $('slice-options'));
      // A slice job opens on its own function, unless that is a lookup the
      // page has not got (custom): marble then.
      const fn = $('slice-options').querySelector('[data-option=function]');
      fn.value = mode === 'slice' && finished.params.slice.function !== 'custom' ? finished.params.slice.function : 'marble';
      fn.dispatchEvent(new Event('change', { bubbles: true }));
      const slider = $('slice-index');
      slider.max = finished.grid.dims[2] - 1;
      slider.value = Math.floor(finished.grid.dims[2] / 2);
      addSliders();
      $('slice-made').textContent = '';
      $('slice-make').disabled = !meshesSent.has(finished.id);
      update();
    },
  };
})();

async function showReport(job) {
  const report = await reportOf(job);
  // A region's row shows where it is: its box in the 3D view.
  renderReport($('report'), report, job.mesh, (min, max) => {
    if (!viewer) return;
    viewer.showBox(min, max);
    if (min) selectTab('view3d');
  });
}

// Fetches `url` (with the API key) and saves its bytes under the name its
// Content-Disposition gives, else `fallback`.
async function saveFrom(url, fallback) {
  const res = await call(url);
  const name = /filename="?([^";]+)"?/.exec(res.headers.get('Content-Disposition') || '');
  const save = Object.assign(document.createElement('a'), {
    href: URL.createObjectURL(await res.blob()), download: name ? name[1] : fallback,
  });
  save.click();
  setTimeout(() => URL.revokeObjectURL(save.href), 10000);
}

// The job's report as one HTML file to send (GET /v1/jobs/{id}/report):
// the pictures, tables, verdict, warnings and inputs; it prints to PDF.
$('download-report').onclick = guarded(async () => {
  if (current?.job) await saveFrom(`/v1/jobs/${current.job.id}/report`, `${current.job.id}-report.html`);
});

function showDownloads(job) {
  const downloads = job.links.downloads || {};
  $('downloads').replaceChildren(...Object.entries(downloads).map(([format, url]) => {
    const a = Object.assign(document.createElement('a'), { href: url, textContent: format, download: '' });
    a.dataset.format = format;
    // A link cannot send the API key: with one, fetch and save the bytes.
    a.onclick = guarded(async (e) => {
      if (!apiKey.get()) return;
      e.preventDefault();
      await saveFrom(url, `${job.id}.${format}`);
    });
    const li = document.createElement('li');
    li.append(a);
    return li;
  }));
}

// ---- start --------------------------------------------------------------------

$('api-key').value = apiKey.get();
$('api-key').onchange = (e) => { apiKey.set(e.target.value.trim()); refreshJobs(); };
guarded(loadSchema)();
refreshJobs();
setInterval(refreshJobs, 5000);
