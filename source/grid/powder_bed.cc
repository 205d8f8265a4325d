// femp: seeded random sequential packing of spherical powder grains.
#include <femp/grid/powder_bed.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>

namespace femp
{
  PowderBed
  pack_powder_bed(const PowderBedSpec &spec)
  {
    const int                              dim = spec.dim;
    const int                              v   = dim - 1; // vertical direction
    std::mt19937_64                        rng(spec.seed);
    std::normal_distribution<double>       diameter(spec.mean_diameter,
                                              spec.std_diameter);
    std::uniform_real_distribution<double> unit(0., 1.);

    double layer_volume = 1;
    for (int d = 0; d < dim; ++d)
      layer_volume *= spec.upper[d] - spec.lower[d];
    if (spec.fill_volume > 0) // recoating: the space above the surface
      layer_volume = spec.fill_volume;
    auto grain_volume = [dim](const double r) {
      return dim == 3 ? 4. / 3. * M_PI * r * r * r : M_PI * r * r;
    };

    // Draw diameters until their volume covers the target; place the large
    // ones first (they are hardest to fit).
    std::vector<double> radii;
    double              target = spec.packing_fraction * layer_volume, sum = 0;
    const double        thickness = spec.upper[v] - spec.lower[v];
    while (sum < target)
      {
        double dia = diameter(rng);
        dia        = std::clamp(dia,
                         spec.min_diameter,
                         std::min(spec.max_diameter, thickness));
        radii.push_back(0.5 * dia);
        sum += grain_volume(0.5 * dia);
      }
    std::sort(radii.begin(), radii.end(), std::greater<double>());
    PowderBed bed;
    bed.achieved_packing_fraction = 0;
    if (radii.empty())
      return bed; // nothing to place (packing fraction or layer volume 0)

    // Grains by vertical column of width = largest diameter.
    const double bin = 2 * radii.front();
    auto column_key  = [&](const std::array<double, 3> &c, int i, int j) {
      const std::int64_t a =
        static_cast<std::int64_t>(std::floor((c[0] - spec.lower[0]) / bin)) + i;
      const std::int64_t b =
        dim == 3 ?
           static_cast<std::int64_t>(std::floor((c[1] - spec.lower[1]) / bin)) +
            j :
           0;
      return a * 1000003 + b;
    };
    std::unordered_multimap<std::int64_t, std::size_t> columns;

    double placed = 0;
    for (const double r : radii)
      {
        for (unsigned int attempt = 0;
             attempt < spec.max_attempts / radii.size() + 50;
             ++attempt)
          {
            // Drop the grain at a random horizontal position: it comes to
            // rest on the substrate or on the first grain it touches.
            std::array<double, 3> c{{0, 0, 0}};
            for (int d = 0; d < dim - 1; ++d)
              c[d] =
                spec.lower[d] + unit(rng) * (spec.upper[d] - spec.lower[d]);
            double z = spec.lower[v] + r;
            if (spec.rest_height) // recoating: on the surface below
              z = std::max(z, spec.rest_height(c, r));
            // Periodic lateral faces (recoating): every grain placed, at
            // its nearest image.
            if (spec.periodic)
              for (const Grain &g : bed.grains)
                {
                  double d2 = 0;
                  for (int d = 0; d < dim - 1; ++d)
                    {
                      const double L  = spec.upper[d] - spec.lower[d];
                      double       dx = g.center[d] - c[d];
                      dx -= L * std::round(dx / L);
                      d2 += dx * dx;
                    }
                  const double rr = (g.radius + r) * (g.radius + r);
                  if (d2 < rr)
                    z = std::max(z, g.center[v] + std::sqrt(rr - d2));
                }
            for (int i = -1; i <= 1 && !spec.periodic; ++i)
              for (int j = (dim == 3 ? -1 : 0); j <= (dim == 3 ? 1 : 0); ++j)
                {
                  const auto range = columns.equal_range(column_key(c, i, j));
                  for (auto it = range.first; it != range.second; ++it)
                    {
                      const Grain &g  = bed.grains[it->second];
                      double       d2 = 0;
                      for (int d = 0; d < dim - 1; ++d)
                        d2 += (g.center[d] - c[d]) * (g.center[d] - c[d]);
                      const double rr = (g.radius + r) * (g.radius + r);
                      if (d2 < rr)
                        z = std::max(z, g.center[v] + std::sqrt(rr - d2));
                    }
                }
            c[v]               = z;
            const bool overlap = z + r > spec.upper[v];
            if (!overlap)
              {
                columns.emplace(column_key(c, 0, 0), bed.grains.size());
                bed.grains.push_back({c, r});
                placed += grain_volume(r);
                break;
              }
          }
      }
    bed.achieved_packing_fraction = placed / layer_volume;
    return bed;
  }
} // namespace femp
