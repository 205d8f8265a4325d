// Every shipped scene (prm/*.prm, prm/validation/*.prm) and material file
// (prm/materials/*.prm) parses with femp's full parameter set, and its
// material, laser and solid data pass femp's checks; nothing is run. For each
// scene, also whether putting 'include materials/316L.prm' in front of it would
// change any material value the scene uses (Material, with the evaporation
// data, and Solid/Material when the solid is solved): a scene for which nothing
// changes could include the file instead of relying on the built-in defaults.
// Last, a scene in tests/ that includes a material file by a path relative to
// itself is read from another working directory.
#include <femp/base/parameter_file.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <vector>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;
namespace fs = std::filesystem;

namespace
{
  /// The values that a material file sets, as {subsection path, entry}.
  const std::vector<std::pair<std::vector<std::string>, std::string>>
    material_entries = {{{"Material"}, "Density"},
                        {{"Material"}, "Specific heat"},
                        {{"Material"}, "Thermal conductivity"},
                        {{"Material"}, "Solidus temperature"},
                        {{"Material"}, "Liquidus temperature"},
                        {{"Material"}, "Latent heat of fusion"},
                        {{"Material"}, "Latent heat of evaporation"},
                        {{"Material"}, "Evaporation temperature"},
                        {{"Material"}, "Molar mass"},
                        {{"Solid", "Material"}, "Young's modulus"},
                        {{"Solid", "Material"}, "Plastic modulus"},
                        {{"Solid", "Material"}, "Yield stress"},
                        {{"Solid", "Material"}, "Poisson's ratio"},
                        {{"Solid", "Material"},
                         "Thermal expansion coefficient"}};

  std::string
  get(ParameterHandler               &prm,
      const std::vector<std::string> &path,
      const std::string              &entry)
  {
    for (const auto &s : path)
      prm.enter_subsection(s);
    const std::string v = prm.get(entry);
    for (std::size_t i = 0; i < path.size(); ++i)
      prm.leave_subsection();
    return v;
  }

  /// Whether two entry values say the same: the same text, or the same
  /// numbers in the same order (2.68e5 and 268000 are one value).
  bool
  same_value(const std::string &a, const std::string &b)
  {
    if (a == b)
      return true;
    const auto numbers = [](const std::string &text) {
      std::vector<double> v;
      std::string         t = text;
      for (char &c : t)
        if (c == ',' || c == ':')
          c = ' ';
      std::istringstream in(t);
      std::string        word;
      while (in >> word)
        {
          char        *end = nullptr;
          const double x   = std::strtod(word.c_str(), &end);
          if (*end != '\0')
            return std::vector<double>();
          v.push_back(x);
        }
      return v;
    };
    const auto va = numbers(a);
    return !va.empty() && va == numbers(b);
  }

  /// Parse @p text (named @p name in messages) and check the data.
  void
  parse_and_check(ParameterHandler  &prm,
                  const std::string &text,
                  const std::string &name)
  {
    declare_all_parameters(prm);
    std::istringstream in(text);
    prm.parse_input(in, name);
    Material material;
    material.parse_parameters(prm);
    SolidMaterial solid(material);
    solid.parse_parameters(prm);
    if (prm.get_integer("Dimension") == 2)
      {
        Laser<2>::Parameters laser;
        laser.parse_parameters(prm);
      }
    else
      {
        Laser<3>::Parameters laser;
        laser.parse_parameters(prm);
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  Checks                           checks(MPI_COMM_WORLD);
  const fs::path                   prm_dir   = argv[1];
  const fs::path                   tests_dir = argv[2];
  const std::string                material_316L =
    (prm_dir / "materials" / "316L.prm").string();

  std::vector<fs::path> files;
  for (const auto &dir :
       {prm_dir, prm_dir / "materials", prm_dir / "validation"})
    for (const auto &f : fs::directory_iterator(dir))
      if (f.path().extension() == ".prm")
        files.push_back(f.path());
  std::sort(files.begin(), files.end());

  unsigned int failures = 0;
  for (const auto &f : files)
    {
      const std::string name =
        f.parent_path().filename().string() + "/" + f.filename().string();
      std::string status = "parses", same_as_316L;
      try
        {
          ParameterHandler scene;
          parse_and_check(scene, resolve_includes(f.string()), f.string());
          if (f.parent_path().filename() != "materials")
            {
              ParameterHandler with, defaults;
              parse_and_check(with,
                              "include " + material_316L + "\n" +
                                resolve_includes(f.string()),
                              f.string());
              parse_and_check(defaults, "", "defaults");
              scene.enter_subsection("Physics");
              const bool solid = scene.get_bool("Solid stress");
              scene.leave_subsection();
              std::vector<std::string> changed;
              bool                     own = false;
              for (const auto &[path, entry] : material_entries)
                if (solid || path[0] != "Solid")
                  {
                    own = own || !same_value(get(scene, path, entry),
                                             get(defaults, path, entry));
                    if (!same_value(get(scene, path, entry),
                                    get(with, path, entry)))
                      changed.push_back(entry);
                  }
              same_as_316L =
                own ? "its own material" : "the default material (316L)";
              same_as_316L +=
                changed.empty() ?
                  "; including materials/316L.prm changes nothing" :
                  "; including materials/316L.prm changes ";
              for (std::size_t i = 0; i < changed.size(); ++i)
                same_as_316L += (i > 0 ? ", " : "") + changed[i];
            }
        }
      catch (const std::exception &e)
        {
          status = std::string("FAILED: ") + e.what();
          ++failures;
        }
      std::cout << name << ": " << status;
      if (!same_as_316L.empty())
        std::cout << "; " << same_as_316L;
      std::cout << std::endl;
    }
  checks.at_most("files that fail to parse", failures, 0);

  // tests/material_include.prm includes ../prm/materials/IN625.prm by a
  // path relative to itself; the test runs in the build tree.
  ParameterHandler prm;
  declare_all_parameters(prm);
  parse_parameter_file(prm, (tests_dir / "material_include.prm").string());
  prm.enter_subsection("Material");
  checks.at_most("IN625 included from tests/: |density - 8440| (kg/m^3)",
                 std::abs(prm.get_double("Density") - 8440.),
                 0);
  prm.leave_subsection();
  return checks.exit_code();
}
