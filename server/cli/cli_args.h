#pragma once
// A small command-line parser: positional arguments plus --flag VALUE /
// --flag=VALUE / boolean --flag. Unknown flags are errors, not silently ignored.
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace voxd::cli {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  // `valued`: flags that take a value; `booleans`: flags that don't.
  Args(int argc, char** argv, int first, const std::set<std::string>& valued, const std::set<std::string>& booleans);

  const std::vector<std::string>& positional() const { return positional_; }
  std::optional<std::string> value(const std::string& flag) const;  // the last one given
  // Every value of a flag given more than once, in order.
  std::vector<std::string> values(const std::string& flag) const;
  bool has(const std::string& flag) const { return flags_.count(flag) > 0; }

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> flags_;
  std::map<std::string, std::vector<std::string>> all_;
};

// Parses "a,b,c" into three numbers; throws UsageError naming the flag.
std::vector<double> parse_number_list(const std::string& text, std::size_t count, const std::string& flag);
std::string read_text_file(const std::string& path);

}  // namespace voxd::cli
