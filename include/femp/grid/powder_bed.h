// femp: random packing of spherical powder grains (doc/method.md, "Zones and
// discretizations"): grain diameters drawn from a normal distribution truncated
// to [d_min, d_max], largest first, each dropped vertically at a random
// horizontal position until it rests on the substrate or touches a grain below
// it (ballistic deposition without rolling); a grain that would stick out of
// the layer is dropped again elsewhere. Stops at the target packing fraction or
// when the attempts run out. The generator is seeded, so every rank builds the
// same bed and a run is reproducible. Pure geometry: no deal.II dependency.
#ifndef femp_powder_bed_h
#define femp_powder_bed_h

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace femp
{
  struct Grain
  {
    std::array<double, 3> center; ///< m (unused coordinates 0)
    double                radius; ///< m
  };

  struct PowderBedSpec
  {
    int                   dim = 3;
    std::array<double, 3> lower{}, upper{}; ///< layer box, m (vertical = dim-1)
    double                mean_diameter    = 30e-6;
    double                std_diameter     = 5e-6;
    double                min_diameter     = 15e-6;
    double                max_diameter     = 45e-6;
    double                packing_fraction = 0.5;
    std::uint64_t         seed             = 1;
    unsigned int          max_attempts     = 200000;
    /// Recoating (builds/recoater.h): the lowest centre height at which a
    /// grain of radius r dropped at horizontal position c rests on the
    /// surface below the layer (the re-solidified track and the powder
    /// beside it); empty: the flat bottom lower[dim-1] of the box.
    std::function<double(const std::array<double, 3> &c, double r)> rest_height;
    /// Recoating: the volume between that surface and the top of the box,
    /// which the packing fraction refers to; 0: the box's volume.
    double fill_volume = 0;
    /// Recoating: the lateral faces are periodic (a grain near one face
    /// rests on the grains near the opposite one, at their nearest image);
    /// false: grains may cross the lateral faces and are cut there.
    bool periodic = false;
  };

  struct PowderBed
  {
    std::vector<Grain> grains;
    double             achieved_packing_fraction = 0;
  };

  /// Pack grains into the layer box. Grains lie entirely inside the box in
  /// the vertical direction and may cross the lateral faces (they are cut by
  /// the domain later).
  PowderBed
  pack_powder_bed(const PowderBedSpec &spec);
} // namespace femp

#endif
