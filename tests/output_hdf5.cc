// Output/Format = hdf5 read back: the scene given as argument (2D or 3D, set
// by its 'Dimension') runs twice, writing VTU and then HDF5 + XDMF with a
// selection of grid fields and point properties. The test then
//  - parses grid.xdmf and points.xdmf (a small XML reader: well-formed,
//    elements nested as the XDMF schema allows, required attributes with
//    allowed values, one Time/Geometry/Topology per uniform grid),
//  - opens every HDF5 dataset a DataItem names (HDF5 C API) and checks that
//    it exists with the stated dimensions, number type and precision, that
//    the geometry, topology and attributes (on nodes or cells) agree in
//    their sizes and that the cells only reference existing nodes,
//  - compares the temperature of every cell (matched by its centre) and of
//    every material point (matched by its id) with the VTU output,
//  - checks that the indices list only existing files and no temporary
//    index is left behind.
// Every number printed is global, so 1 and 2 ranks print the same.
#include <deal.II/base/utilities.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <hdf5.h>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <zlib.h>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  /// One XML element: its name, attributes, text, parent and children.
  struct Element
  {
    std::string                        name, text;
    std::map<std::string, std::string> attributes;
    int                                parent = -1;
    std::vector<int>                   children;
  };

  /// Parse an XML document into a flat list of elements (0: the root);
  /// throws on anything not well-formed.
  std::vector<Element>
  parse_xml(const std::string &s)
  {
    std::vector<Element> elements;
    std::vector<int>     open;
    std::size_t          i = 0;
    const std::regex     attribute(
      "\\s*([A-Za-z_:][-A-Za-z0-9_:.]*)\\s*=\\s*\"([^\"]*)\"");
    while ((i = s.find('<', i)) != std::string::npos)
      {
        if (s.compare(i, 4, "<!--") == 0)
          {
            i = s.find("-->", i);
            AssertThrow(i != std::string::npos, ExcMessage("open comment"));
            continue;
          }
        const std::size_t end = s.find('>', i);
        AssertThrow(end != std::string::npos, ExcMessage("open tag"));
        std::string       tag        = s.substr(i + 1, end - i - 1);
        const std::size_t text_start = end + 1;
        i                            = end + 1;
        if (tag[0] == '?' || tag[0] == '!')
          continue;
        if (tag[0] == '/')
          {
            AssertThrow(!open.empty() && elements[open.back()].name ==
                                           Utilities::trim(tag.substr(1)),
                        ExcMessage("mismatched closing tag </" + tag.substr(1) +
                                   ">"));
            open.pop_back();
            continue;
          }
        const bool self_closing = tag.back() == '/';
        if (self_closing)
          tag.pop_back();
        Element     e;
        std::size_t n    = tag.find_first_of(" \t\n");
        e.name           = tag.substr(0, n);
        std::string rest = n == std::string::npos ? "" : tag.substr(n);
        for (std::smatch m; std::regex_search(rest, m, attribute);
             rest = m.suffix())
          {
            AssertThrow(Utilities::trim(m.prefix()).empty(),
                        ExcMessage("bad attribute in <" + e.name + ">"));
            e.attributes[m[1]] = m[2];
          }
        AssertThrow(Utilities::trim(rest).empty(),
                    ExcMessage("bad attribute in <" + e.name + ">"));
        AssertThrow(!open.empty() || elements.empty(),
                    ExcMessage("a second root element"));
        e.parent = open.empty() ? -1 : open.back();
        if (!self_closing)
          {
            const std::size_t next = s.find('<', text_start);
            e.text = Utilities::trim(s.substr(text_start, next - text_start));
          }
        elements.push_back(e);
        const int id = elements.size() - 1;
        if (e.parent >= 0)
          elements[e.parent].children.push_back(id);
        if (!self_closing)
          open.push_back(id);
      }
    AssertThrow(open.empty() && !elements.empty(),
                ExcMessage("unclosed elements or empty document"));
    return elements;
  }

  /// The XDMF schema's rules femp's files must follow: allowed children of
  /// each element and required attributes with their allowed values.
  void
  check_xdmf_schema(const std::vector<Element> &x)
  {
    const std::map<std::string, std::set<std::string>> children = {
      {"Xdmf", {"Domain"}},
      {"Domain", {"Grid"}},
      {"Grid", {"Grid", "Time", "Geometry", "Topology", "Attribute"}},
      {"Geometry", {"DataItem"}},
      {"Topology", {"DataItem"}},
      {"Attribute", {"DataItem"}},
      {"Time", {}},
      {"DataItem", {}}};
    const std::map<std::string, std::map<std::string, std::set<std::string>>>
      required = {{"Grid", {{"GridType", {"Uniform", "Collection"}}}},
                  {"Geometry", {{"GeometryType", {"XY", "XYZ"}}}},
                  {"Topology",
                   {{"TopologyType",
                     {"Polyvertex", "Polyline", "Quadrilateral", "Hexahedron"}},
                    {"NumberOfElements", {}}}},
                  {"Attribute",
                   {{"Name", {}},
                    {"AttributeType", {"Scalar", "Vector", "Tensor"}},
                    {"Center", {"Node", "Cell"}}}},
                  {"Time", {{"Value", {}}}},
                  {"DataItem",
                   {{"Dimensions", {}},
                    {"NumberType", {"Float", "Int", "UInt", "Char", "UChar"}},
                    {"Format", {"HDF"}}}}};
    AssertThrow(x[0].name == "Xdmf", ExcMessage("root is not <Xdmf>"));
    for (const auto &e : x)
      {
        AssertThrow(children.count(e.name),
                    ExcMessage("unknown element <" + e.name + ">"));
        for (const int c : e.children)
          AssertThrow(children.at(e.name).count(x[c].name),
                      ExcMessage("<" + x[c].name + "> inside <" + e.name +
                                 ">"));
        if (required.count(e.name))
          for (const auto &[attribute, values] : required.at(e.name))
            {
              AssertThrow(e.attributes.count(attribute),
                          ExcMessage("<" + e.name + "> without " + attribute));
              AssertThrow(values.empty() ||
                            values.count(e.attributes.at(attribute)),
                          ExcMessage("<" + e.name + " " + attribute + "=\"" +
                                     e.attributes.at(attribute) + "\">"));
            }
        if (e.name == "Grid" && e.attributes.at("GridType") == "Collection")
          AssertThrow(e.attributes.count("CollectionType") &&
                        e.attributes.at("CollectionType") == "Temporal",
                      ExcMessage("a collection that is not Temporal"));
        if (e.name == "Grid" && e.attributes.at("GridType") == "Uniform")
          for (const std::string part : {"Time", "Geometry", "Topology"})
            {
              int count = 0;
              for (const int c : e.children)
                count += x[c].name == part;
              AssertThrow(count == 1,
                          ExcMessage("a uniform grid without exactly one <" +
                                     part + ">"));
            }
        if (e.name == "DataItem" && e.attributes.at("NumberType") == "Float")
          AssertThrow(e.attributes.count("Precision") &&
                        (e.attributes.at("Precision") == "4" ||
                         e.attributes.at("Precision") == "8"),
                      ExcMessage("a Float DataItem without Precision 4 or 8"));
      }
  }

  std::vector<hsize_t>
  parse_dimensions(const std::string &text)
  {
    std::vector<hsize_t> d;
    for (const auto &w : Utilities::split_string_list(text, ' '))
      if (!w.empty())
        d.push_back(std::stoull(w));
    return d;
  }

  /// A dataset of an HDF5 file read as doubles, with its dimensions and
  /// type; throws if it does not exist.
  struct Dataset
  {
    std::vector<hsize_t> dims;
    H5T_class_t          type_class;
    std::size_t          type_size;
    std::vector<double>  values;
  };

  Dataset
  read_dataset(const std::string &file, const std::string &name)
  {
    AssertThrow(std::filesystem::exists(file),
                ExcMessage("missing HDF5 file " + file));
    const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    AssertThrow(f >= 0, ExcMessage("cannot open " + file));
    AssertThrow(H5Lexists(f, name.c_str(), H5P_DEFAULT) > 0,
                ExcMessage("no dataset " + name + " in " + file));
    const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
    const hid_t s = H5Dget_space(d);
    const hid_t t = H5Dget_type(d);
    Dataset     r;
    r.dims.resize(H5Sget_simple_extent_ndims(s));
    H5Sget_simple_extent_dims(s, r.dims.data(), nullptr);
    r.type_class  = H5Tget_class(t);
    r.type_size   = H5Tget_size(t);
    std::size_t n = 1;
    for (const auto k : r.dims)
      n *= k;
    r.values.resize(n);
    AssertThrow(H5Dread(d,
                        H5T_NATIVE_DOUBLE,
                        H5S_ALL,
                        H5S_ALL,
                        H5P_DEFAULT,
                        r.values.data()) >= 0,
                ExcMessage("cannot read " + name + " in " + file));
    H5Tclose(t);
    H5Sclose(s);
    H5Dclose(d);
    H5Fclose(f);
    return r;
  }

  /// What an XDMF index holds: per uniform grid (time) its datasets.
  struct XdmfSummary
  {
    unsigned int             grids = 0, items = 0;
    std::vector<std::string> attributes; ///< names in the last grid
    std::string              last_file;  ///< h5 file of the last attributes
  };

  /// Check every DataItem of @p index against its HDF5 dataset, and the
  /// sizes of each grid's parts against each other.
  XdmfSummary
  check_xdmf(const std::string &directory, const std::string &index)
  {
    std::ifstream     in(directory + "/" + index);
    std::stringstream buffer;
    buffer << in.rdbuf();
    const auto x = parse_xml(buffer.str());
    check_xdmf_schema(x);
    XdmfSummary summary;
    for (const auto &grid : x)
      {
        if (grid.name != "Grid" || grid.attributes.at("GridType") != "Uniform")
          continue;
        ++summary.grids;
        summary.attributes.clear();
        hsize_t n_nodes = 0, n_cells = 0, n_node_index = 0;
        for (const int c : grid.children)
          {
            const auto &part = x[c];
            if (part.name == "Time")
              continue;
            if (part.name == "Topology" && part.children.empty())
              {
                // Polyvertex: one cell per node, no connectivity needed.
                AssertThrow(part.attributes.at("TopologyType") == "Polyvertex",
                            ExcMessage("a topology without connectivity"));
                n_cells = std::stoull(part.attributes.at("NumberOfElements"));
                n_node_index = n_cells;
                continue;
              }
            AssertThrow(part.children.size() == 1,
                        ExcMessage("<" + part.name + "> without one DataItem"));
            const auto &item = x[part.children[0]];
            const auto  at   = item.text.find(':');
            AssertThrow(at != std::string::npos,
                        ExcMessage("DataItem text is not file:/dataset"));
            const std::string file = item.text.substr(0, at);
            const auto        data =
              read_dataset(directory + "/" + file, item.text.substr(at + 1));
            const auto dims =
              parse_dimensions(item.attributes.at("Dimensions"));
            AssertThrow(dims == data.dims,
                        ExcMessage(item.text +
                                   ": dimensions differ from the "
                                   "DataItem's " +
                                   item.attributes.at("Dimensions")));
            const std::string type = item.attributes.at("NumberType");
            AssertThrow((type == "Float") == (data.type_class == H5T_FLOAT),
                        ExcMessage(item.text + ": number type differs"));
            if (type == "Float")
              AssertThrow(std::to_string(data.type_size) ==
                            item.attributes.at("Precision"),
                          ExcMessage(item.text + ": precision differs"));
            ++summary.items;
            if (part.name == "Geometry")
              {
                n_nodes = dims[0];
                AssertThrow(dims.size() == 2 &&
                              dims[1] ==
                                (part.attributes.at("GeometryType") == "XY" ?
                                   2u :
                                   3u),
                            ExcMessage("geometry of the wrong shape"));
              }
            else if (part.name == "Topology")
              {
                AssertThrow(n_nodes > 0,
                            ExcMessage("topology before geometry"));
                n_cells = dims[0];
                AssertThrow(std::to_string(n_cells) ==
                              part.attributes.at("NumberOfElements"),
                            ExcMessage("NumberOfElements differs from the "
                                       "topology's dimensions"));
                for (const double v : data.values)
                  n_node_index = std::max<hsize_t>(n_node_index, v + 1);
              }
            else
              {
                summary.attributes.push_back(part.attributes.at("Name"));
                summary.last_file   = file;
                const bool on_cells = part.attributes.at("Center") == "Cell";
                AssertThrow(dims.size() == 2 && dims[1] == 1 &&
                              dims[0] == (on_cells ? n_cells : n_nodes),
                            ExcMessage(part.attributes.at("Name") +
                                       ": not one value per node or cell"));
              }
          }
        AssertThrow(n_nodes > 0 && n_cells > 0 && n_node_index <= n_nodes,
                    ExcMessage("cells reference nodes that do not exist"));
      }
    return summary;
  }

  /// The values of the DataArray @p name (Float32/Int32, zlib-compressed,
  /// base64) of a VTU piece written by deal.II.
  template <typename T>
  std::vector<T>
  vtu_array(const std::string &vtu, const std::string &name)
  {
    const std::string key =
      name.empty() ? "NumberOfComponents=\"3\"" : "Name=\"" + name + "\"";
    std::size_t k = vtu.find(key);
    AssertThrow(k != std::string::npos, ExcMessage("no " + name + " in VTU"));
    k = vtu.find('>', k) + 1;
    const std::string text =
      Utilities::trim(vtu.substr(k, vtu.find('<', k) - k));
    if (text.empty()) // a piece without points
      return {};
    const auto    head = Utilities::decode_base64(text.substr(0, 24));
    const auto    data = Utilities::decode_base64(text.substr(24));
    std::uint32_t h[4];
    std::memcpy(h, head.data(), sizeof(h));
    std::vector<T> values(h[1] / sizeof(T));
    uLongf         size = h[1];
    AssertThrow(uncompress(reinterpret_cast<Bytef *>(values.data()),
                           &size,
                           data.data(),
                           data.size()) == Z_OK,
                ExcMessage("cannot decompress " + name));
    return values;
  }

  std::string
  read_file(const std::string &name)
  {
    std::ifstream     in(name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  /// Cell centres (rounded to 1e-9 of the largest coordinate) -> value of
  /// @p field, from the nodes, cells and field arrays of either format.
  std::map<std::vector<long>, double>
  by_centre(const std::vector<double> &nodes,
            const unsigned int         dim,
            const std::vector<double> &cells,
            const unsigned int         corners,
            const std::vector<double> &field,
            const bool                 on_cells)
  {
    std::map<std::vector<long>, double> m;
    for (std::size_t c = 0; c < cells.size() / corners; ++c)
      {
        std::vector<double> x(dim, 0.);
        for (unsigned int v = 0; v < corners; ++v)
          for (unsigned int d = 0; d < dim; ++d)
            x[d] +=
              nodes[std::size_t(cells[c * corners + v]) * dim + d] / corners;
        std::vector<long> key(dim);
        for (unsigned int d = 0; d < dim; ++d)
          key[d] = std::lround(x[d] * 1e9);
        m[key] = on_cells ? field[c] : field[std::size_t(cells[c * corners])];
      }
    return m;
  }

  /// Largest difference between the HDF5 and the VTU values of the cells
  /// (by centre) or the points (by id) of output @p n; -1 if the sets of
  /// cells or points differ.
  double
  compare_with_vtu(const std::string &h5_dir,
                   const std::string &vtu_dir,
                   const std::string &kind,
                   const std::string &field,
                   const unsigned int dim,
                   const unsigned int n,
                   std::size_t       &count,
                   double            &max_value,
                   unsigned int      &empty_pieces)
  {
    const std::string number = Utilities::int_to_string(n, 5);
    const bool        points = kind == "points";
    const std::string mesh =
      h5_dir + "/" + (points ? kind + "_" + number : "grid_mesh") + ".h5";
    const std::string file  = h5_dir + "/" + kind + "_" + number + ".h5";
    const auto        value = read_dataset(file, "/" + field).values;
    std::map<std::vector<long>, double> h5, vtu;
    if (points)
      {
        const auto id = read_dataset(file, "/id").values;
        for (std::size_t i = 0; i < id.size(); ++i)
          h5[{std::lround(id[i])}] = value[i];
      }
    else
      h5 = by_centre(read_dataset(mesh, "/nodes").values,
                     dim,
                     read_dataset(mesh, "/cells").values,
                     1u << dim,
                     value,
                     true);
    // VTU pieces: every grid_<n>.<piece>.vtu of the output.
    const std::regex piece(kind + "_" + number + "\\.[0-9]+\\.vtu");
    for (const auto &entry : std::filesystem::directory_iterator(vtu_dir))
      {
        if (!std::regex_match(entry.path().filename().string(), piece))
          continue;
        const std::string s = read_file(entry.path().string());
        const auto        v = vtu_array<float>(s, field);
        empty_pieces += v.empty();
        if (points)
          {
            const auto id = vtu_array<float>(s, "id");
            for (std::size_t i = 0; i < id.size(); ++i)
              vtu[{std::lround(id[i])}] = v[i];
            continue;
          }
        const auto          xyz  = vtu_array<float>(s, "");
        const auto          conn = vtu_array<std::int32_t>(s, "connectivity");
        std::vector<double> x;
        for (std::size_t i = 0; i < xyz.size(); i += 3)
          for (unsigned int d = 0; d < dim; ++d)
            x.push_back(xyz[i + d]);
        const auto m = by_centre(x,
                                 dim,
                                 std::vector<double>(conn.begin(), conn.end()),
                                 1u << dim,
                                 std::vector<double>(v.begin(), v.end()),
                                 false);
        vtu.insert(m.begin(), m.end());
      }
    count     = h5.size();
    max_value = 0;
    for (const auto &kv : h5)
      max_value = std::max(max_value, kv.second);
    if (h5.size() != vtu.size())
      return -1;
    double diff = 0;
    for (const auto &[key, value] : h5)
      {
        const auto it = vtu.find(key);
        if (it == vtu.end())
          return -1;
        diff = std::max(diff, std::abs(value - it->second));
      }
    return diff;
  }

  template <int dim>
  int
  run(const std::string           &prm_file,
      MPI_Comm                     comm,
      const std::vector<Override> &scene)
  {
    Checks                checks(comm);
    std::vector<Override> common = {{"Output", "Output interval", "0"},
                                    {"Output",
                                     "Write material points",
                                     "always"},
                                    {"Output", "Probe lines", ""}};
    common.insert(common.end(), scene.begin(), scene.end());
    auto vtu = common, h5 = common;
    vtu.push_back({"Output", "Directory", "output_vtu"});
    h5.push_back({"Output", "Directory", "output_h5"});
    h5.push_back({"Output", "Format", "hdf5"});
    h5.push_back({"Output", "Grid fields", "T, phase, subdomain"});
    h5.push_back({"Output", "Point properties", "temperature, state"});
    run_scene<dim>(prm_file, comm, vtu);
    run_scene<dim>(prm_file, comm, h5);
    if (Utilities::MPI::this_mpi_process(comm) != 0)
      return 0;
    for (const std::string kind : {"grid", "points"})
      {
        const auto s = check_xdmf("output_h5", kind + ".xdmf");
        std::cout << kind << ".xdmf: " << s.grids << " outputs, " << s.items
                  << " DataItems found in the HDF5 files with their "
                     "dimensions; attributes:";
        for (const auto &a : s.attributes)
          std::cout << ' ' << a;
        std::cout << std::endl;
        std::size_t  count = 0;
        double       T_max = 0;
        unsigned int empty = 0;
        const double diff =
          compare_with_vtu("output_h5",
                           "output_vtu",
                           kind,
                           kind == "grid" ? "T" : "temperature",
                           dim,
                           1,
                           count,
                           T_max,
                           empty);
        if (empty > 0) // ranks that had nothing to write
          std::cout << kind << ": " << empty << " VTU pieces are empty"
                    << std::endl;
        std::cout << kind << ": " << count
                  << (kind == "grid" ? " cells" : " points")
                  << " compared with the VTU output, largest T "
                  << std::setprecision(6) << T_max << " K" << std::endl;
        checks.in_range(kind + ": largest |T(HDF5) - T(VTU)| (K)", diff, 0, 0);
      }
    unsigned int tmp = 0;
    for (const auto &dir : {"output_h5", "output_vtu"})
      for (const auto &entry : std::filesystem::directory_iterator(dir))
        tmp += entry.path().extension() == ".tmp";
    checks.in_range("temporary index files left", tmp, 0, 0);
    return checks.exit_code();
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  // Arguments: the scene, then overrides 'Section/Entry=value'.
  std::vector<Override> scene;
  for (int i = 2; i < argc; ++i)
    {
      const std::string a     = argv[i];
      const auto        slash = a.rfind('/', a.find('='));
      scene.push_back({a.substr(0, slash),
                       a.substr(slash + 1, a.find('=') - slash - 1),
                       a.substr(a.find('=') + 1)});
    }
  // The scene's dimension decides which program runs.
  ParameterHandler prm;
  femp::declare_all_parameters(prm);
  prm.parse_input(argv[1]);
  const int dim = prm.get_integer("Dimension");
  return dim == 2 ? run<2>(argv[1], comm, scene) : run<3>(argv[1], comm, scene);
}
