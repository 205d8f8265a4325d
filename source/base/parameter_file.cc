// femp: scene files with 'include' lines relative to the scene's folder
// (include/femp/base/parameter_file.h).
#include <femp/base/input_checks.h>
#include <femp/base/parameter_file.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace femp
{
  std::string
  resolve_includes(const std::string &file)
  {
    namespace fs = std::filesystem;
    std::ifstream in(file);
    require(static_cast<bool>(in), "scene file", file,
            "the file does not exist or cannot be read");
    const fs::path    folder = fs::path(file).parent_path();
    std::ostringstream out;
    std::string        line;
    while (std::getline(in, line))
      {
        const auto first = line.find_first_not_of(" \t");
        if (first != std::string::npos &&
            (line.compare(first, 8, "include ") == 0 ||
             line.compare(first, 8, "INCLUDE ") == 0))
          {
            std::string name = line.substr(first + 8);
            const auto  hash = name.find('#');
            if (hash != std::string::npos)
              name.erase(hash);
            name = dealii::Utilities::trim(name);
            const fs::path beside = folder / name;
            if (!name.empty() && fs::path(name).is_relative() &&
                fs::exists(beside))
              line = line.substr(0, first) + "include " + beside.string();
          }
        out << line << '\n';
      }
    return out.str();
  }


  void
  parse_parameter_file(dealii::ParameterHandler &prm, const std::string &file)
  {
    std::istringstream text(resolve_includes(file));
    prm.parse_input(text, file);
  }
} // namespace femp
