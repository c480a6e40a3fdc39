#include "server/cli/cli_args.h"
#include "voxd/encode/number_text.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace voxd::cli {

Args::Args(int argc, char** argv, int first, const std::set<std::string>& valued,
           const std::set<std::string>& booleans) {
  for (int i = first; i < argc; ++i) {
    std::string a = argv[i];
    if (a.size() > 2 && a.rfind("--", 0) == 0) {
      std::string name = a.substr(2), val;
      bool inline_value = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        val = name.substr(eq + 1);
        name = name.substr(0, eq);
        inline_value = true;
      }
      if (valued.count(name)) {
        if (!inline_value) {
          if (i + 1 >= argc) throw UsageError("--" + name + " needs a value");
          val = argv[++i];
        }
        flags_[name] = val;
        all_[name].push_back(val);
      } else if (booleans.count(name) && !inline_value) {
        flags_[name] = "";
      } else {
        throw UsageError("unknown option --" + name);
      }
    } else if (a == "-o") {
      if (i + 1 >= argc) throw UsageError("-o needs a value");
      flags_["output"] = argv[++i];
    } else {
      positional_.push_back(a);
    }
  }
}

std::vector<std::string> Args::values(const std::string& flag) const {
  auto it = all_.find(flag);
  return it == all_.end() ? std::vector<std::string>{} : it->second;
}

std::optional<std::string> Args::value(const std::string& flag) const {
  auto it = flags_.find(flag);
  if (it == flags_.end()) return std::nullopt;
  return it->second;
}

std::vector<double> parse_number_list(const std::string& text, std::size_t count, const std::string& flag) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const std::optional<double> v = parse_number<double>(item);
    if (!v || !std::isfinite(*v))
      throw UsageError("--" + flag + " expects " + std::to_string(count) + " comma-separated numbers, got '" + text + "'");
    out.push_back(*v);
  }
  if (out.size() != count)
    throw UsageError("--" + flag + " expects " + std::to_string(count) + " comma-separated numbers, got '" + text + "'");
  return out;
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError("cannot read '" + path + "': " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace voxd::cli
