// The Kubernetes manifests in deploy/kubernetes/ against the Kubernetes API's
// own schemas (kubernetes-models from npm, pinned in web/package-lock.json:
// each object validated by its apiVersion and kind, as the API server's
// OpenAPI validation would), so a misspelt field or a wrong value type fails
// here, not at `kubectl apply`. docs/scale-out.md says how they are used.
//   node --test tests/web/kubernetes_manifests_test.mjs
import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { join } from 'node:path';
import test from 'node:test';

import { repo, requireWebModule } from './voxd_server.mjs';

const yaml = requireWebModule('js-yaml');
const folder = join(repo, 'deploy/kubernetes');

// The model class of an object: kubernetes-models/<group>/<version>/<Kind>
// (the core group's objects under its version alone).
function modelOf({ apiVersion, kind }) {
  return requireWebModule(`kubernetes-models/${apiVersion}/${kind}`)[kind];
}

function objects() {
  const out = [];
  for (const file of readdirSync(folder).filter((f) => f.endsWith('.yaml')))
    for (const object of yaml.loadAll(readFileSync(join(folder, file), 'utf8')))
      if (object) out.push({ file, object });
  return out;
}

test('every object of the Kubernetes manifests is valid for its kind', () => {
  const all = objects();
  assert.ok(all.length >= 8, `only ${all.length} objects read`);
  for (const { file, object } of all) {
    assert.doesNotThrow(() => new (modelOf(object))(object).validate(), `${file}: ${object.kind} ${object.metadata?.name}`);
  }
});

test('the validation catches what kubectl would refuse', () => {
  const deployment = objects().find(({ object }) => object.kind === 'Deployment').object;
  const broken = structuredClone(deployment);
  broken.spec.template.spec.containers[0].imagePullPolicy = 'Sometimes';
  assert.throws(() => new (modelOf(broken))(broken).validate(), /imagePullPolicy/);
  const typo = structuredClone(deployment);
  typo.spec.replicas = 'two';
  assert.throws(() => new (modelOf(typo))(typo).validate(), /replicas/);
});

test('no two manifests define the same object', () => {
  const seen = new Map();
  for (const { file, object } of objects()) {
    const key = `${object.kind}/${object.metadata?.namespace ?? ''}/${object.metadata?.name}`;
    assert.ok(!seen.has(key), `${key} in ${seen.get(key)} and ${file}`);
    seen.set(key, file);
  }
});
