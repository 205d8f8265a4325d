// femp: scene files with 'include' lines and scan-path files relative to the
// folder of the file that names them, at any depth
// (include/femp/base/parameter_file.h).
#include <deal.II/base/exceptions.h>
#include <deal.II/base/utilities.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_file.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>
#include <utility>
#include <vector>

namespace femp
{
  namespace
  {
    namespace fs = std::filesystem;

    /// Resolved copies of included files that include further files by
    /// relative paths: (copy, original). deal.II opens an included file by
    /// itself, relative to the working directory, so such a file is handed
    /// to it as a copy whose own include lines are resolved. The copies
    /// are removed when the program ends.
    struct ResolvedCopies
    {
      std::vector<std::pair<std::string, std::string>> files;
      ~ResolvedCopies()
      {
        std::error_code ec;
        for (const auto &f : files)
          fs::remove(f.first, ec);
      }
    };
    ResolvedCopies resolved_copies;

    /// The name an include line names, or "" if @p line is no include.
    std::string
    included_name(const std::string &line, std::size_t &first)
    {
      first = line.find_first_not_of(" \t");
      if (first == std::string::npos ||
          (line.compare(first, 8, "include ") != 0 &&
           line.compare(first, 8, "INCLUDE ") != 0))
        return "";
      std::string name = line.substr(first + 8);
      const auto  hash = name.find('#');
      if (hash != std::string::npos)
        name.erase(hash);
      return dealii::Utilities::trim(name);
    }

    /// For a line 'set Scan path file = NAME': NAME, which stands in
    /// @p line at [@p begin, @p end); "" for any other line.
    std::string
    scan_path_name(const std::string &line,
                   std::size_t       &begin,
                   std::size_t       &end)
    {
      const std::size_t first = line.find_first_not_of(" \t");
      if (first == std::string::npos || (line.compare(first, 4, "set ") != 0 &&
                                         line.compare(first, 4, "SET ") != 0))
        return "";
      const std::size_t eq = line.find('=', first);
      if (eq == std::string::npos)
        return "";
      // The entry's name, its blanks collapsed as deal.II does.
      std::string entry;
      for (std::size_t i = first + 4; i < eq; ++i)
        if (line[i] != ' ' && line[i] != '\t')
          entry += line[i];
        else if (!entry.empty() && entry.back() != ' ')
          entry += ' ';
      if (dealii::Utilities::trim(entry) != "Scan path file")
        return "";
      end = std::min(line.find('#', eq), line.size());
      while (end > eq + 1 && (line[end - 1] == ' ' || line[end - 1] == '\t'))
        --end;
      begin = line.find_first_not_of(" \t", eq + 1);
      if (begin == std::string::npos || begin >= end)
        return "";
      return line.substr(begin, end - begin);
    }

    std::string
    resolve(const std::string &file, const unsigned int depth)
    {
      require(depth < 16,
              "include",
              file,
              "includes are nested more than 16 deep (does a file include "
              "itself?)");
      std::ifstream in(file);
      require(static_cast<bool>(in),
              depth == 0 ? "scene file" : "include",
              file,
              "the file does not exist or cannot be read");
      const fs::path     folder = fs::path(file).parent_path();
      std::ostringstream out;
      std::string        line;
      while (std::getline(in, line))
        {
          std::size_t       first  = 0;
          const std::string name   = included_name(line, first);
          const fs::path    beside = folder / name;
          if (!name.empty() && fs::path(name).is_relative() &&
              fs::exists(beside) && !fs::is_directory(beside))
            {
              // The included file as deal.II should read it: itself if it
              // has no include of its own to resolve, else a resolved copy
              // (the same lines, so deal.II's line numbers stay right).
              std::ifstream     original(beside);
              std::stringstream raw;
              raw << original.rdbuf();
              const std::string text   = resolve(beside.string(), depth + 1);
              std::string       target = beside.string();
              if (text != raw.str() && text + "\n" != raw.str() &&
                  text != raw.str() + "\n")
                {
                  static unsigned int n = 0;
                  target =
                    (fs::temp_directory_path() /
                     ("femp-" + std::to_string(::getpid()) + "-" +
                      std::to_string(n++) + "-" + beside.filename().string()))
                      .string();
                  std::ofstream copy(target);
                  copy << text;
                  require(static_cast<bool>(copy),
                          "include",
                          beside.string(),
                          "a resolved copy could not be written to " + target);
                  resolved_copies.files.emplace_back(target, beside.string());
                }
              line = line.substr(0, first) + "include " + target;
            }
          // A relative scan-path file found next to this file: named by
          // its path from the working directory (else left to be looked
          // for there).
          std::size_t       begin = 0, end = 0;
          const std::string scan = scan_path_name(line, begin, end);
          if (!scan.empty() && !folder.empty() && fs::path(scan).is_relative())
            {
              const fs::path path = folder / scan;
              if (fs::exists(path) && !fs::is_directory(path))
                line = line.substr(0, begin) +
                       path.lexically_normal().string() + line.substr(end);
            }
          out << line << '\n';
        }
      return out.str();
    }
  } // namespace

  std::string
  resolve_includes(const std::string &file)
  {
    return resolve(file, 0);
  }

  void
  parse_parameter_file(dealii::ParameterHandler &prm, const std::string &file)
  {
    std::istringstream text(resolve_includes(file));
    try
      {
        prm.parse_input(text, file);
      }
    catch (const dealii::ExceptionBase &e)
      {
        // deal.II names the resolved copy of an included file: name the
        // file the user wrote instead.
        std::string msg  = e.what();
        const auto  info = msg.find("Additional information:");
        if (info != std::string::npos)
          msg = msg.substr(info + 23);
        const auto trace = msg.find("Stacktrace:");
        if (trace != std::string::npos)
          msg = msg.substr(0, trace);
        for (const auto &f : resolved_copies.files)
          for (std::size_t pos = msg.find(f.first); pos != std::string::npos;
               pos             = msg.find(f.first, pos + f.second.size()))
            msg.replace(pos, f.first.size(), f.second);
        AssertThrow(false, dealii::ExcMessage(msg));
      }
  }

  std::string
  unopened_file(const std::string &file)
  {
    if (!fs::path(file).is_relative())
      return "the file cannot be opened";
    return "the file cannot be opened (a relative path is looked for next "
           "to the scene file that names it, then in the directory femp is "
           "started in, " +
           fs::current_path().string() + ")";
  }
} // namespace femp
