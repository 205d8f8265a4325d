// femp: reading a scene file whose 'include' lines name files relative to
// the scene's own folder (deal.II's ParameterHandler opens them relative to
// the working directory, so a scene that includes a material file, e.g.
// 'include materials/316L.prm' in prm/, would only run from one folder),
// and whose scan-path file is named relative to the scene's folder too.
#ifndef femp_parameter_file_h
#define femp_parameter_file_h

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace femp
{
  /// Parse @p file into @p prm as ParameterHandler::parse_input() does,
  /// except that the relative path of an 'include' line is looked up first
  /// next to @p file, then (as deal.II does) in the working directory; the
  /// same holds inside included files, at any depth (up to 16 levels), so a
  /// scene may include a scene that includes a material file. The relative
  /// path of a 'set Scan path file = NAME' line is looked up the same way:
  /// next to the file that holds the line first, then in the working
  /// directory (a scene and its scan path run from any folder).
  void
  parse_parameter_file(dealii::ParameterHandler &prm, const std::string &file);

  /// The text of @p file with its 'include' paths resolved as above.
  std::string
  resolve_includes(const std::string &file);

  /// What an input error says when the file @p file that a parameter names
  /// cannot be opened (for a relative path, where it was looked for).
  std::string
  unopened_file(const std::string &file);
} // namespace femp

#endif
