#include "server/http/openapi_document.h"

#include <map>
#include <stdexcept>

namespace voxd::server {
namespace {

using json = nlohmann::json;

// "file#/a/b" -> "#/components/schemas/Name/a/b"; "#/a" inside file -> the same.
class RefRewriter {
 public:
  explicit RefRewriter(std::map<std::string, std::string> component_of_file)
      : component_of_file_(std::move(component_of_file)) {}

  void rewrite(json& node, const std::string* own_component) const {
    if (node.is_array()) {
      for (auto& item : node) rewrite(item, own_component);
      return;
    }
    if (!node.is_object()) return;
    for (auto& [key, value] : node.items()) {
      if (key == "$ref" && value.is_string())
        value = target(value.get<std::string>(), own_component);
      else
        rewrite(value, own_component);
    }
  }

 private:
  std::string target(const std::string& ref, const std::string* own_component) const {
    const auto hash = ref.find('#');
    const std::string file = ref.substr(0, hash);
    const std::string pointer = hash == std::string::npos ? "" : ref.substr(hash + 1);
    if (file.empty()) {
      // A fragment of the document it sits in: the main document's stay as
      // they are, an embedded schema's now live under its component.
      return own_component ? "#/components/schemas/" + *own_component + pointer : ref;
    }
    const auto it = component_of_file_.find(file);
    if (it == component_of_file_.end())
      throw std::runtime_error("openapi: $ref \"" + ref + "\" names a file the served document does not embed");
    return "#/components/schemas/" + it->second + pointer;
  }

  std::map<std::string, std::string> component_of_file_;
};

}  // namespace

nlohmann::json bundle_openapi(nlohmann::json document, const std::vector<ExternalSchema>& schemas) {
  auto& components = document.at("components").at("schemas");
  std::map<std::string, std::string> component_of_file;
  for (auto& [name, schema] : components.items()) {
    if (schema.is_object() && schema.size() == 1 && schema.contains("$ref") && schema["$ref"].is_string() &&
        schema["$ref"].get<std::string>().find('#') == std::string::npos)
      component_of_file[schema["$ref"].get<std::string>()] = name;
  }
  const RefRewriter rewriter(component_of_file);
  rewriter.rewrite(document, nullptr);  // before the schemas move in: their refs are rewritten below
  for (const auto& external : schemas) {
    const auto it = component_of_file.find(external.file);
    if (it == component_of_file.end())
      throw std::runtime_error("openapi: no component schema stands for " + external.file);
    json schema = external.schema;
    schema.erase("$id");
    schema.erase("$schema");
    rewriter.rewrite(schema, &it->second);
    components[it->second] = std::move(schema);
  }
  for (const auto& [file, name] : component_of_file) {
    const auto& component = components[name];
    if (component.size() == 1 && component.contains("$ref") && component["$ref"].is_string() &&
        component["$ref"].get<std::string>() == "#/components/schemas/" + name)
      throw std::runtime_error("openapi: " + file + " (component " + name + ") was not embedded");
  }
  return document;
}

const std::string& served_openapi_document() {
  static const std::string text =
      bundle_openapi(json::parse(kOpenApiSource), {{"job-params.schema.json", json::parse(kJobParamsSchema)},
                                                   {"analysis.schema.json", json::parse(kAnalysisSchema)}})
          .dump(2);
  return text;
}

}  // namespace voxd::server
