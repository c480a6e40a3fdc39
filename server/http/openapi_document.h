#pragma once
// The OpenAPI document voxd serves at GET /openapi.json: one self-contained
// document, so that a client, a code generator or a linter that fetches it
// alone resolves every $ref.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace voxd::server {

// The texts of proto-schemas/ as they were at build time.
extern const char* const kOpenApiSource;    // openapi.json
extern const char* const kJobParamsSchema;  // job-params.schema.json
extern const char* const kAnalysisSchema;   // analysis.schema.json

struct ExternalSchema {
  std::string file;  // as the document's $ref names it, e.g. "job-params.schema.json"
  nlohmann::json schema;
};

// In the repository the document refers to the JSON Schemas beside it: a
// component schema that is exactly {"$ref": "<file>"} stands for the whole
// file. This moves each such file into its component, rewrites the $refs
// inside it (its own "#/$defs/..." and the other files') to paths in the one
// document, and drops its $id and $schema (an $id would make a resolver read
// those paths against the file's URL again). Throws std::runtime_error when a
// $ref names a file it was not given, so a new schema file cannot be
// forgotten.
nlohmann::json bundle_openapi(nlohmann::json document, const std::vector<ExternalSchema>& schemas);

// The bundled document as served, built once.
const std::string& served_openapi_document();

}  // namespace voxd::server
