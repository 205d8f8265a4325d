// femp: the thermo-elasto-plastic constitutive model of the solid (paper
// eq. 5, doc/method.md, "Solid"), shared by the material points (SolidMPM) and
// the finite elements (SolidFEM).
//
// Hypoelastic-plastic, rate form, one explicit increment per solid step:
//   D = sym(L), W = skew(L)             (L: velocity gradient)
//   D_e = D - D_p - alpha dT/dt I       (thermal strain rate beta T', with
//                                        beta = 3 kappa alpha, i.e. the
//                                        thermal stress modulus)
//   sigma^Jaumann = C(T) : D_e + (E'(T) T' / E(T)) sigma
// The last term makes the elasticity of total form, sigma = C(T) : eps_e
// with the elastic strain eps_e as the state (free energy 1/2 eps_e : C(T) :
// eps_e): when E falls with temperature the stress falls with it (in the
// update: sigma <- sigma E(T_new)/E(T_old) before the increment; Poisson's
// ratio is constant, so C(T_new) C(T_old)^-1 = E(T_new)/E(T_old)). With an
// E(T) table that falls to a small value at the solidus the stress of a
// heated point goes continuously to (almost) zero before it melts (see
// doc/solid.md "Constitutive model"). The pure rate form without that term
// would keep the pressure built at low temperature.
// Objective update: sigma* = R sigma R^T with the Hughes-Winget rotation
// R = (I - W dt/2)^-1 (I + W dt/2) (exactly orthogonal, so a rigid rotation
// leaves the invariants unchanged), then the elastic predictor with the
// moduli at the new temperature (the old stress first scaled by
// E(T_new)/E(T_old), see above), then J2 radial return with linear
// isotropic hardening:
//   f = q - (sigma_y(T) + H(T) eps_p),  q = sqrt(3/2 s:s),
//   d_gamma = f / (3 mu + H),  s <- s (1 - 3 mu d_gamma / q_trial).
// Young's modulus E(T), plastic (hardening) modulus H(T) = d sigma_y/d eps_p
// and the initial yield stress sigma_y(T) are piecewise-linear temperature
// tables. A point at or above the solidus carries no stress and no plastic
// strain (melted); when it solidifies it therefore starts stress-free.
//
// Stresses are always 3x3 (in 2D: plane strain, the out-of-plane stress
// sigma_zz is carried as a state variable). Only deal.II tensors are used,
// so this header stays light.
//
// update_stress_block: the same update for simd_lanes states at once (GCC
// vector extension simd_double; the elastic path in SIMD, yielding or
// melted lanes through a scalar fallback), for the FE element and MPM
// point loops.
#ifndef femp_constitutive_h
#define femp_constitutive_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

#include <femp/base/input_checks.h>
#include <femp/base/material.h>
#include <femp/base/parameter_table.h>

#include <cmath>

namespace femp
{
  using namespace dealii;

  struct SolidMaterial
  {
    /// The solid data of the metal of @p thermal, whose density and solidus
    /// it reads (declared once, in Material); @p thermal must outlive it.
    explicit SolidMaterial(const Material &thermal)
        : thermal(&thermal)
    {
    }

    PiecewiseLinear youngs_modulus{1.93e11}; ///< E(T), Pa
    PiecewiseLinear plastic_modulus{1e9};    ///< H(T), Pa
    PiecewiseLinear yield_stress{2.5e8};     ///< sigma_y(T), Pa
    double          poisson_ratio = 0.3;     ///< nu, -
    double          expansion     = 1.7e-5;  ///< alpha, 1/K (linear)
    /// Linear artificial bulk viscosity b1 (numerical, -): a viscous
    /// pressure q = b1 rho c h tr(D) added to the stress in the force
    /// computation (not stored), which damps the ringing behind stress
    /// fronts of the explicit scheme (von Neumann-Richtmyer, linear term).
    double bulk_viscosity = 0.1;
    /// Velocity transfer of the material points (SolidMPM, numerical):
    /// FLIP (v_p += dt sum N a_I) or APIC (affine particle-in-cell, Jiang et
    /// al. 2015: each point carries C_p = sum v_I (x) grad N; parameter
    /// "Solid/Velocity transfer").
    enum class VelocityTransfer
    {
      flip,
      apic
    };
    VelocityTransfer velocity_transfer = VelocityTransfer::apic;
    /// Where the material points of the solid (SolidMPM, numerical) take
    /// the volumetric part of their velocity gradient (parameter
    /// "Solid/Volumetric strain rate"): point (each point the divergence of
    /// the multilinear nodal velocity field at its own position) or
    /// centroid (every point of a cell the divergence at the volume
    /// centroid of the cell's points; the deviatoric part stays the
    /// point's; the pressure's nodal forces then use the tent gradients at
    /// the centroid, the transpose of that rate: a B-bar treatment, Hughes
    /// 1980).
    enum class VolumetricStrainRate
    {
      point,
      centroid
    };
    VolumetricStrainRate volumetric_strain_rate = VolumetricStrainRate::point;
    /// Nodal smoothing of the material points' mean-stress increment
    /// (parameter "Solid/Pressure smoothing"): after each stress update
    /// the increment of tr(sigma)/3 of every solid point is replaced by
    /// its volume-weighted projection to the grid nodes interpolated back
    /// to the point; the deviator stays the point's. Removes the
    /// cell-to-cell checkerboard of the mean stress, the pressure mode
    /// that the points' nodal forces do not see (SolidMPM).
    bool pressure_smoothing = false;

    /// Declares the entries of subsection "Solid/Material".
    /// Declare (the members' values are the defaults) or read the
    /// entries, each listed once.
    void
    add_parameters(ParameterTable &table);
    static void
    declare_parameters(ParameterHandler &prm);
    /// Reads subsection "Solid/Material" (density and solidus are the
    /// Material's).
    void
    parse_parameters(ParameterHandler &prm);

    /// rho, kg/m^3: Material/Density.
    double
    density() const
    {
      return thermal->density;
    }
    /// The solidus T_s, K (Material/Solidus temperature): a point at or
    /// above it is melted and carries no stress.
    double
    melt_temperature() const
    {
      return thermal->solidus;
    }

    /// Largest P-wave modulus M = E (1-nu) / ((1+nu)(1-2nu)) of the table, Pa.
    double
    max_p_wave_modulus() const;
    /// P-wave modulus at temperature @p T, Pa.
    double
    p_wave_modulus(const double T) const
    {
      const double nu = poisson_ratio;
      return youngs_modulus.value(T) * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    }

  private:
    const Material *thermal;
  };

  /// Stored elastic energy density sigma : C(T)^-1 : sigma / 2 (J/m^3) of
  /// the stress @p s {xx, yy, zz, xy, xz, yz} at temperature @p T
  /// (isotropic: ((1 + nu) sigma:sigma - nu tr(sigma)^2) / (2 E(T))); used
  /// by the adaptive mass scaling (doc/speed_accuracy.md, section 3).
  inline double
  elastic_energy_density(const SolidMaterial &m,
                         const double        *s,
                         const double         T)
  {
    const double nu = m.poisson_ratio;
    const double tr = s[0] + s[1] + s[2];
    const double ss = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] +
                      2 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
    return ((1 + nu) * ss - nu * tr * tr) / (2 * m.youngs_modulus.value(T));
  }

  /// Stress state of one material point or one Gauss point.
  struct StressPoint
  {
    SymmetricTensor<2, 3> sigma;      ///< Cauchy stress, Pa
    double                eps_p = 0.; ///< equivalent plastic strain, -
  };

  /// Result of one increment, for the energy bookkeeping.
  struct StressIncrement
  {
    bool   yielded           = false;
    double plastic_increment = 0.; ///< d_gamma
  };

  /// Advance @p state over one step: @p L_dt is the velocity gradient times
  /// the step (3x3; zero third row and column in 2D, plane strain),
  /// @p T_old and @p T_new the temperatures at the start and end of the step.
  StressIncrement
  update_stress(const SolidMaterial &m,
                const Tensor<2, 3>  &L_dt,
                const double         T_old,
                const double         T_new,
                StressPoint         &state);

  /// The same update on plain arrays, for point loops (SolidMPM): @p L_dt
  /// row-major 3x3, @p s the stress {xx, yy, zz, xy, xz, yz}, @p eps_p the
  /// equivalent plastic strain. Returns the plastic increment d_gamma (0 when
  /// elastic). Cheap paths that are exact: the rotation is skipped when the
  /// spin is below 1e-18 (it would change no stress digit), and the
  /// hardening table is read only when the trial stress exceeds the initial
  /// yield stress.
  [[gnu::always_inline]] inline double
  update_stress_array(const SolidMaterial &m,
                      const double (&L_dt)[3][3],
                      const double T_old,
                      const double T_new,
                      const double E_old,
                      const double E,
                      double (&s)[6],
                      double &eps_p);

  inline double
  update_stress_array(const SolidMaterial &m,
                      const double (&L_dt)[3][3],
                      const double T_old,
                      const double T_new,
                      double (&s)[6],
                      double &eps_p)
  {
    if (T_new >= m.melt_temperature())
      {
        for (auto &c : s)
          c = 0;
        eps_p = 0;
        return 0;
      }
    return update_stress_array(m,
                               L_dt,
                               T_old,
                               T_new,
                               m.youngs_modulus.value(T_old),
                               m.youngs_modulus.value(T_new),
                               s,
                               eps_p);
  }

  /// The same with Young's moduli @p E_old = E(T_old) and @p E = E(T_new)
  /// given by the caller (who needs E anyway, e.g. for the hourglass
  /// stiffness and the viscous pressure of an element), so that the table
  /// is read once per step. Always inlined: the element and point loops
  /// keep L and the stress in registers.
  [[gnu::always_inline]] inline double
  update_stress_array(const SolidMaterial &m,
                      const double (&L_dt)[3][3],
                      const double T_old,
                      const double T_new,
                      const double E_old,
                      const double E,
                      double (&s)[6],
                      double &eps_p)
  {
    if (T_new >= m.melt_temperature())
      {
        for (auto &c : s)
          c = 0;
        eps_p = 0;
        return 0;
      }
    // Total-form elasticity: the elastic strain is kept, the stress follows
    // E (exactly 1 for a constant E).
    const double r  = E / E_old;
    double       xx = r * s[0], yy = r * s[1], zz = r * s[2], xy = r * s[3],
           xz = r * s[4], yz = r * s[5];
    const double w01 = 0.5 * (L_dt[0][1] - L_dt[1][0]);
    const double w02 = 0.5 * (L_dt[0][2] - L_dt[2][0]);
    const double w12 = 0.5 * (L_dt[1][2] - L_dt[2][1]);
    const double ww  = w01 * w01 + w02 * w02 + w12 * w12;
    if (ww > 1e-36)
      {
        // R = I + f (W + W^2/2), f = 1 / (1 + |w|^2/4) (Cayley form of the
        // Hughes-Winget rotation), sigma <- R sigma R^T.
        const double W[3][3] = {{0, w01, w02}, {-w01, 0, w12}, {-w02, -w12, 0}};
        const double f       = 1. / (1 + 0.25 * ww);
        double       R[3][3];
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = 0; j < 3; ++j)
            R[i][j] =
              (i == j ? 1. : 0.) +
              f * (W[i][j] + 0.5 * (W[i][0] * W[0][j] + W[i][1] * W[1][j] +
                                    W[i][2] * W[2][j]));
        const double S[3][3] = {{xx, xy, xz}, {xy, yy, yz}, {xz, yz, zz}};
        double       RS[3][3];
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = 0; j < 3; ++j)
            RS[i][j] =
              R[i][0] * S[0][j] + R[i][1] * S[1][j] + R[i][2] * S[2][j];
        auto rsr = [&](const unsigned int i, const unsigned int j) {
          return RS[i][0] * R[j][0] + RS[i][1] * R[j][1] + RS[i][2] * R[j][2];
        };
        xx = rsr(0, 0), yy = rsr(1, 1), zz = rsr(2, 2);
        xy = rsr(0, 1), xz = rsr(0, 2), yz = rsr(1, 2);
      }
    // Elastic predictor with the moduli at the new temperature; a point that
    // solidified in this step starts stress-free at the solidus.
    const double nu     = m.poisson_ratio;
    const double mu2    = E / (1 + nu);
    const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
    const double dth =
      m.expansion *
      (T_new - (T_old < m.melt_temperature() ? T_old : m.melt_temperature()));
    const double dxx = L_dt[0][0] - dth, dyy = L_dt[1][1] - dth,
                 dzz = L_dt[2][2] - dth;
    const double lt  = lambda * (dxx + dyy + dzz);
    xx += mu2 * dxx + lt;
    yy += mu2 * dyy + lt;
    zz += mu2 * dzz + lt;
    xy += 0.5 * mu2 * (L_dt[0][1] + L_dt[1][0]);
    xz += 0.5 * mu2 * (L_dt[0][2] + L_dt[2][0]);
    yz += 0.5 * mu2 * (L_dt[1][2] + L_dt[2][1]);
    // J2 radial return, linear isotropic hardening.
    const double p = (xx + yy + zz) * (1. / 3);
    xx -= p, yy -= p, zz -= p;
    const double ss =
      xx * xx + yy * yy + zz * zz + 2 * (xy * xy + xz * xz + yz * yz);
    const double sy    = m.yield_stress.value(T_new);
    double       scale = 1, dg = 0;
    if (1.5 * ss > sy * sy) // the hardening term only raises the yield stress
      {
        const double q   = std::sqrt(1.5 * ss);
        const double H   = m.plastic_modulus.value(T_new);
        const double syh = sy + H * eps_p;
        if (q > syh)
          {
            dg    = (q - syh) / (1.5 * mu2 + H);
            scale = 1 - 1.5 * mu2 * dg / q;
            eps_p += dg;
          }
      }
    s[0] = scale * xx + p, s[1] = scale * yy + p, s[2] = scale * zz + p;
    s[3] = scale * xy, s[4] = scale * xz, s[5] = scale * yz;
    return dg;
  }

  /// Lanes of the SIMD block kernels (update_stress_block, the FE element
  /// loop, the 2D MPM point loops): 4 doubles, one AVX2 register.
  constexpr unsigned int simd_lanes = 4;
  /// W doubles as one value (GCC vector extension: element-wise
  /// arithmetic, comparisons give lane masks, mask ? a : b selects; with
  /// -march=native one AVX2 register for W = 4, one AVX-512 register for
  /// W = 8; emulated by narrower registers where the machine has none).
  /// deal.II's VectorizedArray is not used: the Debian build of deal.II is
  /// configured without vectorization (width 1).
  template <unsigned int W>
  struct SimdOf
  {
    typedef double type __attribute__((vector_size(8 * W)));
  };
  /// simd_lanes doubles as one value.
  typedef SimdOf<simd_lanes>::type simd_double;
  /// Lanes of the 3D MPM point loops: 8 (a block is the 2 x 2 x 2 points of
  /// a cell) where the compiler targets AVX-512, else 4. The results do not
  /// depend on it beyond round-off (the node sums of a cell are grouped the
  /// same way; only the lane sums of the energies are taken in another
  /// order). FEMP_MPM_LANES_3D (4 or 8) overrides the choice, to compare.
#if defined(FEMP_MPM_LANES_3D)
  constexpr unsigned int mpm_lanes_3d = FEMP_MPM_LANES_3D;
#elif defined(__AVX512F__)
  constexpr unsigned int mpm_lanes_3d = 8;
#else
  constexpr unsigned int mpm_lanes_3d = 4;
#endif

  /// Number of lanes of a GCC vector type.
  template <typename V>
  constexpr unsigned int simd_width = sizeof(V) / sizeof(double);

  /// Element-wise square root.
  template <typename V>
  inline V
  simd_sqrt(V x)
  {
#if defined(__AVX512F__)
    if constexpr (simd_width<V> == 8)
      return __builtin_ia32_sqrtpd512_mask(x, x, -1, 4);
#endif
#if defined(__AVX__)
    if constexpr (simd_width<V> == 4)
      return __builtin_ia32_sqrtpd256(x);
#endif
    for (unsigned int l = 0; l < simd_width<V>; ++l)
      x[l] = std::sqrt(x[l]);
    return x;
  }

  /// simd_width<V> stress states (lane l: one element or point), for
  /// update_stress_block.
  template <typename V>
  struct StressBlockOf
  {
    V L[3][3];         ///< velocity gradient times the step
    V T_old, T_new, E; ///< K, K, Pa (E = E(T_new))
    V E_old;           ///< E(T_old), Pa
    V s[6];            ///< in: old stress, out: new {xx..yz}
    V eps_p;           ///< in/out
  };
  /// simd_lanes stress states.
  typedef StressBlockOf<simd_double> StressBlock;

  /// update_stress_array() for simd_width<V> states at once, with the same
  /// arithmetic lane by lane (identical results up to the compiler's
  /// contraction of multiply-adds): the elastic path (Hughes-Winget
  /// rotation, computed for all lanes and kept where the spin is above
  /// 1e-18; thermal strain, predictor, yield check) in SIMD; the rare lanes
  /// that yield or melted take a scalar fallback (hardening table, radial
  /// return). The tables of sigma_y are read per lane; the caller sets E
  /// and E_old of every lane. Every lane must hold
  /// finite data (pad a partial block with copies).
  template <typename V>
  [[gnu::always_inline]] inline void
  update_stress_block(const SolidMaterial &m, StressBlockOf<V> &b, const V sy);

  template <typename V>
  [[gnu::always_inline]] inline void
  update_stress_block(const SolidMaterial &m, StressBlockOf<V> &b)
  {
    V sy;
    for (unsigned int l = 0; l < simd_width<V>; ++l)
      sy[l] = m.yield_stress.value(b.T_new[l]);
    update_stress_block(m, b, sy);
  }

  /// The same with the initial yield stress sy = sigma_y(T_new) of every
  /// lane given by the caller (the MPM reads it once per cell: the points
  /// of a cell share its temperature).
  template <typename V>
  [[gnu::always_inline]] inline void
  update_stress_block(const SolidMaterial &m, StressBlockOf<V> &b, const V sy)
  {
    constexpr unsigned int W  = simd_width<V>;
    const double           nu = m.poisson_ratio;
    const V                Tm = V{} + m.melt_temperature();
    // Total-form elasticity (see the top of this file): r = 1 exactly for a
    // constant E.
    const V r  = b.E / b.E_old;
    V       xx = r * b.s[0], yy = r * b.s[1], zz = r * b.s[2], xy = r * b.s[3],
      xz = r * b.s[4], yz = r * b.s[5];
    const V(&L)[3][3] = b.L;
    const V w01       = 0.5 * (L[0][1] - L[1][0]);
    const V w02       = 0.5 * (L[0][2] - L[2][0]);
    const V w12       = 0.5 * (L[1][2] - L[2][1]);
    const V ww        = w01 * w01 + w02 * w02 + w12 * w12;
    {
      // As update_stress_array(), written out: R = I + f (W + W^2/2),
      // sigma <- R sigma R^T.
      const V f   = 1. / (1 + 0.25 * ww);
      const V R00 = 1. + f * (0. + 0.5 * (0. * 0. + w01 * -w01 + w02 * -w02));
      const V R01 = 0. + f * (w01 + 0.5 * (0. * w01 + w01 * 0. + w02 * -w12));
      const V R02 = 0. + f * (w02 + 0.5 * (0. * w02 + w01 * w12 + w02 * 0.));
      const V R10 =
        0. + f * (-w01 + 0.5 * (-w01 * 0. + 0. * -w01 + w12 * -w02));
      const V R11 = 1. + f * (0. + 0.5 * (-w01 * w01 + 0. * 0. + w12 * -w12));
      const V R12 = 0. + f * (w12 + 0.5 * (-w01 * w02 + 0. * w12 + w12 * 0.));
      const V R20 =
        0. + f * (-w02 + 0.5 * (-w02 * 0. + -w12 * -w01 + 0. * -w02));
      const V R21 =
        0. + f * (-w12 + 0.5 * (-w02 * w01 + -w12 * 0. + 0. * -w12));
      const V R22 = 1. + f * (0. + 0.5 * (-w02 * w02 + -w12 * w12 + 0. * 0.));
      const V R[3][3] = {{R00, R01, R02}, {R10, R11, R12}, {R20, R21, R22}};
      const V S[3][3] = {{xx, xy, xz}, {xy, yy, yz}, {xz, yz, zz}};
      V       RS[3][3];
      for (unsigned int i = 0; i < 3; ++i)
        for (unsigned int j = 0; j < 3; ++j)
          RS[i][j] = R[i][0] * S[0][j] + R[i][1] * S[1][j] + R[i][2] * S[2][j];
      auto rsr = [&](const unsigned int i, const unsigned int j) {
        return RS[i][0] * R[j][0] + RS[i][1] * R[j][1] + RS[i][2] * R[j][2];
      };
      const auto spin = ww > 1e-36;
      xx = spin ? rsr(0, 0) : xx, yy = spin ? rsr(1, 1) : yy;
      zz = spin ? rsr(2, 2) : zz, xy = spin ? rsr(0, 1) : xy;
      xz = spin ? rsr(0, 2) : xz, yz = spin ? rsr(1, 2) : yz;
    }
    const V mu2    = b.E / (1 + nu);
    const V lambda = b.E * nu / ((1 + nu) * (1 - 2 * nu));
    const V dth    = m.expansion * (b.T_new - (b.T_old < Tm ? b.T_old : Tm));
    const V dxx = L[0][0] - dth, dyy = L[1][1] - dth, dzz = L[2][2] - dth;
    const V lt = lambda * (dxx + dyy + dzz);
    xx += mu2 * dxx + lt;
    yy += mu2 * dyy + lt;
    zz += mu2 * dzz + lt;
    xy += 0.5 * mu2 * (L[0][1] + L[1][0]);
    xz += 0.5 * mu2 * (L[0][2] + L[2][0]);
    yz += 0.5 * mu2 * (L[1][2] + L[2][1]);
    const V p = (xx + yy + zz) * (1. / 3);
    xx -= p, yy -= p, zz -= p;
    const V ss =
      xx * xx + yy * yy + zz * zz + 2 * (xy * xy + xz * xz + yz * yz);
    const auto melted = b.T_new >= Tm;
    const auto flag   = melted | (1.5 * ss > sy * sy);
    V          scale  = V{} + 1.;
    // Scalar fallback: lanes above the initial yield stress (the hardening
    // term only raises it) and melted lanes.
    for (unsigned int l = 0; l < W; ++l)
      if (flag[l])
        {
          if (melted[l])
            {
              b.eps_p[l] = 0;
              continue;
            }
          const double q   = std::sqrt(1.5 * ss[l]);
          const double H   = m.plastic_modulus.value(b.T_new[l]);
          const double syh = sy[l] + H * b.eps_p[l];
          if (q > syh)
            {
              const double dg = (q - syh) / (1.5 * mu2[l] + H);
              scale[l]        = 1 - 1.5 * mu2[l] * dg / q;
              b.eps_p[l] += dg;
            }
        }
    const V zero = {};
    b.s[0]       = melted ? zero : scale * xx + p;
    b.s[1]       = melted ? zero : scale * yy + p;
    b.s[2]       = melted ? zero : scale * zz + p;
    b.s[3]       = melted ? zero : scale * xy;
    b.s[4]       = melted ? zero : scale * xz;
    b.s[5]       = melted ? zero : scale * yz;
  }

  /// von Mises equivalent stress q = sqrt(3/2 s:s), Pa.
  inline double
  von_mises(const SymmetricTensor<2, 3> &s)
  {
    const SymmetricTensor<2, 3> d = deviator(s);
    return std::sqrt(1.5 * (d * d));
  }
} // namespace femp

#endif
