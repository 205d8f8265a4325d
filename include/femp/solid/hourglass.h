// femp: the Flanagan-Belytschko hourglass control of the FE zone's one-point
// elements (SolidFEM, solid_fem.h; doc/solid.md "Hourglass control and the
// thermal stress"), stiffness form. For the undeformed cube of side h the
// hourglass base vectors Gamma_alpha (products of two or more corner signs
// s_a,d: xy in 2D; xy, xz, yz, xyz in 3D) are orthogonal to the linear
// field, and per element
//   q_alpha,i = sum_a Gamma_alpha,a u_a,i     (mode amplitudes),
//   f_a,i^HG  = -k sum_alpha Gamma_alpha,a q_alpha,i,
//   k = kappa M(T) V (sum_a |b_a|^2) / 2^dim  (M: P-wave modulus),
// with the energy 1/2 k sum q^2. Here: the modes, the stiffness, the
// corner distortion the modes make, the energy. SolidFEM integrates q in
// its fused element loop (these inline functions in it) and adds the
// forces there; its transition-node forces and energy sums over the
// elements are in hourglass.cc.
#ifndef femp_hourglass_h
#define femp_hourglass_h

namespace femp
{
  namespace hourglass
  {
    /// s_a,d = +-1: sign of corner a (bit d set: upper side) in direction d.
    constexpr double
    sgn(const unsigned int a, const unsigned int d)
    {
      return ((a >> d) & 1u) ? 1. : -1.;
    }
    /// H_ma = prod_{d in m} s_a,d: the matrix of the elements'
    /// Walsh-Hadamard transform; H_(mode_mask(alpha)),a = Gamma_alpha,a.
    constexpr double
    hadamard(const unsigned int m, const unsigned int a)
    {
      double h = 1;
      for (unsigned int d = 0; d < 3; ++d)
        if ((m >> d) & 1u)
          h *= sgn(a, d);
      return h;
    }
    /// Number of hourglass modes alpha per direction.
    template <int dim>
    constexpr unsigned int n_modes = dim == 2 ? 1 : 4;
    /// Hourglass base vector alpha as a transform index (a product of two
    /// or more s_d: xy in 2D; xy, xz, yz, xyz in 3D).
    template <int dim>
    constexpr unsigned int
    mode_mask(const unsigned int al)
    {
      return dim == 2 ? 3u : (al == 0 ? 3u : al == 1 ? 5u : al == 2 ? 6u : 7u);
    }
    /// Hourglass stiffness k = kappa M V bb / n_corners, N/m (2D: N/m per
    /// m): @p kappa the coefficient, @p M the P-wave modulus (Pa), @p V the
    /// element volume, @p bb = sum_a |b_a|^2.
    inline double
    stiffness(const double       kappa,
              const double       M,
              const double       V,
              const double       bb,
              const unsigned int n_corners)
    {
      return kappa * M * V * bb / n_corners;
    }
    /// Largest change of a corner's volume ratio that the modes @p q of an
    /// element (or a SIMD block of them) make, to first order: @p hgB times
    /// the sum over the modes alpha and the directions i of alpha of
    /// |q_alpha,i|.
    template <int dim, typename Number>
    [[gnu::always_inline]] inline Number
    distortion(const Number (&q)[n_modes<dim>][dim], const double hgB)
    {
      Number hq = {};
      for (unsigned int al = 0; al < n_modes<dim>; ++al)
        for (int i = 0; i < dim; ++i)
          if (mode_mask<dim>(al) & (1u << i))
            hq += q[al][i] < 0 ? -q[al][i] : q[al][i];
      return hgB * hq;
    }
  } // namespace hourglass
} // namespace femp

#endif
