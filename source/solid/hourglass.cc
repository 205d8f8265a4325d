// femp: the hourglass forces at the transition nodes and the hourglass
// energy of the FE zone's elements (Flanagan-Belytschko, stiffness form;
// see hourglass.h); the amplitudes are integrated and the element forces
// added in SolidFEM's element loop (solid_fem.cc).
#include <femp/solid/hourglass.h>
#include <femp/solid/solid_fem.h>

#include <algorithm>

namespace femp
{
  template <int dim>
  double
  SolidFEM<dim>::hourglass_stiffness(const double T, const double kappa) const
  {
    return hourglass::stiffness(kappa, mat.p_wave_modulus(T), V, bb, n_corners);
  }

  // Hourglass pass at the transition nodes: the hourglass forces of this
  // rank's elements there, kept out of the grid's force and added back
  // locally (eq. 17).
  template <int dim>
  void
  SolidFEM<dim>::transition_hourglass_forces(const double kfac)
  {
    std::fill(tr_hg.begin(), tr_hg.end(), 0.);
    if (!(kfac > 0))
      return;
    for (const auto &tc : tr_corners)
      {
        const ElementBlock &eb = blocks[tc[0] / simd_lanes];
        const unsigned int  l  = tc[0] % simd_lanes;
        const double        k  = kfac * mat.youngs_modulus.value(eb.T[l]);
        for (int i = 0; i < dim; ++i)
          for (unsigned int al = 0; al < n_hg; ++al)
            tr_hg[dim * tc[2] + i] -=
              k * hourglass::hadamard(hourglass::mode_mask<dim>(al), tc[1]) *
              eb.q[al][i][l];
      }
  }

  template <int dim>
  std::array<double, 2>
  SolidFEM<dim>::hourglass_energy(const bool with_reference) const
  {
    // Each energy summed element by element in the same order as a pass of
    // its own would (k as hourglass_stiffness() computes it).
    const double          kappa = prm.hourglass_coefficient, kappa_ref = 0.05;
    std::array<double, 2> energy{{0., 0.}};
    const bool            scene = kappa != 0;
    if (!scene && !with_reference)
      return energy;
    for (std::size_t e = 0; e < element_id.size(); ++e)
      {
        const ElementBlock &eb = blocks[e / simd_lanes];
        const unsigned int  l  = e % simd_lanes;
        const double        M  = mat.p_wave_modulus(eb.T[l]);
        const double k  = hourglass::stiffness(kappa, M, V, bb, n_corners);
        const double kr = hourglass::stiffness(kappa_ref, M, V, bb, n_corners);
        for (unsigned int al = 0; al < n_hg; ++al)
          for (int i = 0; i < dim; ++i)
            {
              const double q = eb.q[al][i][l];
              if (scene)
                energy[0] += 0.5 * k * q * q;
              if (with_reference)
                energy[1] += 0.5 * kr * q * q;
            }
      }
    return energy;
  }

  template double
  SolidFEM<2>::hourglass_stiffness(const double, const double) const;
  template double
  SolidFEM<3>::hourglass_stiffness(const double, const double) const;
  template void
  SolidFEM<2>::transition_hourglass_forces(const double);
  template void
  SolidFEM<3>::transition_hourglass_forces(const double);
  template std::array<double, 2>
  SolidFEM<2>::hourglass_energy(const bool) const;
  template std::array<double, 2>
  SolidFEM<3>::hourglass_energy(const bool) const;
} // namespace femp
