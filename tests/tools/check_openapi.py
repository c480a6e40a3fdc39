#!/usr/bin/env python3
"""Independent checks of voxd's OpenAPI document (python3-jsonschema).

check_openapi.py OPENAPI JOB_PARAMS
    The document is OpenAPI 3.1 whose component schemas are valid JSON Schema
    2020-12, every $ref resolves, every operation documents its responses and
    every 4xx/5xx answer is application/problem+json with the Problem schema.
check_openapi.py OPENAPI JOB_PARAMS --responses DIR
    Every DIR/<Component>.<n>.json (bodies the real service sent, saved by the
    integration tests) validates against components.schemas.<Component>.
"""
import json
import os
import sys

import jsonschema

openapi_path, job_params_path = sys.argv[1], sys.argv[2]
doc = json.load(open(openapi_path))
job_params = json.load(open(job_params_path))
store = {job_params["$id"]: job_params}
# The other published schemas beside the document, by their $id.
schema_dir = os.path.dirname(os.path.abspath(job_params_path))
for name in os.listdir(schema_dir):
    if name.endswith(".schema.json"):
        other = json.load(open(os.path.join(schema_dir, name)))
        store[other["$id"]] = other
# The document's relative $ref "job-params.schema.json" resolves beside it, to
# the job-params schema's $id.
BASE_URI = job_params["$id"].rsplit("/", 1)[0] + "/openapi.json"


def validator_for(component):
    resolver = jsonschema.RefResolver(base_uri=BASE_URI, referrer=doc, store=store)
    return jsonschema.Draft202012Validator({"$ref": "#/components/schemas/" + component}, resolver=resolver)


def fail(message):
    print("openapi:", message)
    sys.exit(1)


if len(sys.argv) == 5 and sys.argv[3] == "--responses":
    folder = sys.argv[4]
    checked = 0
    for name in sorted(os.listdir(folder)):
        component = name.split(".")[0]
        if component not in doc["components"]["schemas"]:
            fail(f"{name}: no component {component}")
        body = json.load(open(os.path.join(folder, name)))
        errors = sorted(validator_for(component).iter_errors(body), key=lambda e: list(e.path))
        if errors:
            fail(f"{name} does not match {component}: " + "; ".join(
                f"{'/'.join(map(str, e.path))}: {e.message}" for e in errors[:5]))
        checked += 1
    print(f"openapi: {checked} response bodies match their schemas")
    sys.exit(0)

if not doc.get("openapi", "").startswith("3.1"):
    fail("not an OpenAPI 3.1 document")
for key in ("info", "paths", "components"):
    if key not in doc:
        fail(f"missing {key}")
for name, schema in doc["components"]["schemas"].items():
    jsonschema.Draft202012Validator.check_schema(schema)
    if schema.get("type") == "object" and schema.get("additionalProperties") is not False:
        fail(f"component {name} must list its fields (additionalProperties: false) so drift is caught")


def refs(node):
    if isinstance(node, dict):
        for k, v in node.items():
            if k == "$ref":
                yield v
            else:
                yield from refs(v)
    elif isinstance(node, list):
        for v in node:
            yield from refs(v)


resolver = jsonschema.RefResolver(base_uri=BASE_URI, referrer=doc, store=store)
for ref in set(refs(doc)):
    try:
        resolver.resolve(ref)
    except jsonschema.RefResolutionError as e:
        fail(f"$ref {ref} does not resolve: {e}")

operations = 0
for path, item in doc["paths"].items():
    for method, op in item.items():
        if method not in ("get", "post", "put", "delete", "patch", "options"):
            continue
        operations += 1
        where = f"{method.upper()} {path}"
        if "operationId" not in op or not op.get("responses"):
            fail(f"{where}: needs operationId and responses")
        for status, response in op["responses"].items():
            if status[0] in "45":
                content = response.get("content", {})
                schema = content.get("application/problem+json", {}).get("schema", {})
                # The readiness probe answers 503 with its Health body, as probes do.
                if path == "/readyz" and content.get("application/json", {}).get("schema", {}).get("$ref") == "#/components/schemas/Health":
                    continue
                if schema.get("$ref") != "#/components/schemas/Problem":
                    fail(f"{where} {status}: errors must be application/problem+json with the Problem schema")
        if "{id}" in path and not any(p.get("name") == "id" for p in item.get("parameters", []) + op.get("parameters", [])):
            fail(f"{where}: the id path parameter is not documented")

# The schemas accept what they should and refuse what they should.
problem = validator_for("Problem")
problem.validate({"type": "urn:voxd:problem:not-found", "title": "Not found", "status": 404, "detail": "no job", "instance": "/v1/jobs/x"})
if problem.is_valid({"type": "urn:voxd:problem:not-found", "status": 404}):
    fail("Problem accepts a body without title and detail")
print(f"openapi: {operations} operations, {len(doc['components']['schemas'])} component schemas valid")
