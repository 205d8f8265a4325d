// femp: the vectorised block kernels of the solid's material point method
// (SolidMPM, solid_mpm.h; paper eqs. 11-13): tent weights and gradients of
// the multilinear cell functions, the per-cell monomial coefficients of the
// nodal velocity interpolant, loads and stores of blocks of consecutive
// points (SIMD lanes, one cell when they share it), the P2G scatter of a
// block, the G2P velocity and MUSL re-map, the velocity gradient and the
// stress update of a block with the constitutive law of constitutive.h.
// Only solid_mpm.cc includes it; the functions are inline templates that
// operate on the flat point and node arrays passed in.
#ifndef femp_mpm_kernels_h
#define femp_mpm_kernels_h

#include <deal.II/base/tensor.h>

#include <femp/solid/constitutive.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <vector>

namespace femp
{
  namespace mpm_kernels
  {
    using namespace dealii;

    /// Index of stress component (i, j) in {xx, yy, zz, xy, xz, yz}.
    constexpr unsigned int
    sidx(const unsigned int i, const unsigned int j)
    {
      return i == j ? i : 2 + i + j; // xy -> 3, xz -> 4, yz -> 5
    }

    /// Tent weights N and gradients dN of the 2^dim corners (corner a has
    /// bit d set when it is the upper node in direction d) at local
    /// coordinates xi, for cell size 1/ih.
    template <int dim, typename Number>
    [[gnu::always_inline]] inline void
    tents(const Number (&xi)[dim],
          const double ih,
          Number (&N)[1 << dim],
          Number (&dN)[1 << dim][dim])
    {
      Number w[dim][2];
      double g[2] = {-ih, ih};
      for (int d = 0; d < dim; ++d)
        w[d][0] = 1 - xi[d], w[d][1] = xi[d];
      for (unsigned int a = 0; a < (1u << dim); ++a)
        {
          const unsigned int b0 = a & 1, b1 = (a >> 1) & 1;
          if constexpr (dim == 2)
            {
              N[a]     = w[0][b0] * w[1][b1];
              dN[a][0] = g[b0] * w[1][b1];
              dN[a][1] = w[0][b0] * g[b1];
            }
          else
            {
              const unsigned int b2  = (a >> 2) & 1;
              const Number       w12 = w[1][b1] * w[2][b2];
              N[a]                   = w[0][b0] * w12;
              dN[a][0]               = g[b0] * w12;
              dN[a][1]               = w[0][b0] * g[b1] * w[2][b2];
              dN[a][2]               = w[0][b0] * w[1][b1] * g[b2];
            }
        }
    }

    /// Lanes of the point loops: mpm_lanes_3d in 3D (8 with AVX-512: a
    /// block is then the 2 x 2 x 2 points of a cell), simd_lanes (4) in 2D
    /// (2 x 2 points per cell).
    template <int dim>
    constexpr unsigned int point_lanes = dim == 3 ? mpm_lanes_3d : simd_lanes;

    /// Lanes p[0..W-1] of @p a as one vector (a full block of consecutive
    /// points: one vector load).
    template <std::size_t W>
    inline typename SimdOf<W>::type
    simd_load(const std::vector<double> &a,
              const std::size_t (&p)[W],
              const bool full)
    {
      typename SimdOf<W>::type r;
      if (full)
        std::memcpy(&r, &a[p[0]], sizeof(r));
      else
        for (unsigned int l = 0; l < W; ++l)
          r[l] = a[p[l]];
      return r;
    }
    /// A block of up to W consecutive points starting at p0 (of n): nl
    /// lanes in use, their indices pl (unused lanes repeat the last point,
    /// so loads stay in range), full when every lane is used.
    template <unsigned int W>
    struct PointBlock
    {
      PointBlock(const std::size_t p0, const std::size_t n)
          : nl(std::min<std::size_t>(W, n - p0))
          , full(nl == W)
      {
        for (unsigned int l = 0; l < W; ++l)
          pl[l] = p0 + std::min(l, nl - 1);
      }
      unsigned int nl;
      bool         full;
      std::size_t  pl[W];
    };

    /// True when the W lanes of @p n0 are equal (the points of the block
    /// lie in one cell).
    template <std::size_t W>
    inline bool
    one_cell(const std::size_t (&n0)[W])
    {
      bool r = true;
      for (unsigned int l = 1; l < W; ++l)
        r = r && n0[l] == n0[0];
      return r;
    }

    /// Calls @p coefficients with the loader of the corner values of the
    /// block @p n0: one cell's node values broadcast to all lanes when the
    /// W points lie in one cell (and only if @p coef_cell does not hold that
    /// cell's coefficients already), else gathered lane by lane.
    /// @p coef_cell becomes the cell whose coefficients were computed, or
    /// none (-1) after a block of several cells.
    template <typename VD, std::size_t W, typename Coefficients>
    [[gnu::always_inline]] inline void
    corner_coefficients(const std::size_t (&n0)[W],
                        std::size_t   &coef_cell,
                        Coefficients &&coefficients)
    {
      if (one_cell(n0))
        {
          if (n0[0] != coef_cell)
            {
              coefficients([&](const double *f, const std::ptrdiff_t o) {
                return VD{} + f[n0[0] + o];
              });
              coef_cell = n0[0];
            }
        }
      else
        {
          coefficients([&](const double *f, const std::ptrdiff_t o) {
            VD r;
            for (unsigned int l = 0; l < W; ++l)
              r[l] = f[n0[l] + o];
            return r;
          });
          coef_cell = std::size_t(-1);
        }
    }

    /// Lanes of @p a summed as a tree: (a0 + a1) + (a2 + a3), and for 8
    /// lanes the sum of the two halves so formed.
    template <typename VD>
    inline double
    lane_total(const VD a)
    {
      static_assert(simd_width<VD> == 4 || simd_width<VD> == 8, "4 or 8");
      const double lo = (a[0] + a[1]) + (a[2] + a[3]);
      if constexpr (simd_width<VD> == 8)
        return lo + ((a[4] + a[5]) + (a[6] + a[7]));
      else
        return lo;
    }

    /// Local coordinates xi of the points of @p b in their cells (origin
    /// @p corner, size 1/ih) and their tent weights and gradients.
    template <int dim,
              typename Arrays,
              unsigned int W,
              typename VD = typename SimdOf<W>::type>
    [[gnu::always_inline]] inline void
    block_tents(const Arrays        &x,
                const Arrays        &corner,
                const PointBlock<W> &b,
                const double         ih,
                VD (&xi)[dim],
                VD (&N)[1 << dim],
                VD (&dN)[1 << dim][dim])
    {
      for (int d = 0; d < dim; ++d)
        xi[d] =
          (simd_load(x[d], b.pl, b.full) - simd_load(corner[d], b.pl, b.full)) *
          ih;
      tents<dim>(xi, ih, N, dN);
    }

    /// Local coordinates xi of the points of @p b in their cells (origin
    /// @p corner, size 1/ih), without the tents.
    template <int dim,
              typename Arrays,
              unsigned int W,
              typename VD = typename SimdOf<W>::type>
    [[gnu::always_inline]] inline void
    block_xi(const Arrays        &x,
             const Arrays        &corner,
             const PointBlock<W> &b,
             const double         ih,
             VD (&xi)[dim])
    {
      for (int d = 0; d < dim; ++d)
        xi[d] =
          (simd_load(x[d], b.pl, b.full) - simd_load(corner[d], b.pl, b.full)) *
          ih;
    }

    /// Tent weights N of the 2^dim corners at xi (the products of tents(),
    /// without the gradients).
    template <int dim, typename VD>
    [[gnu::always_inline]] inline void
    weights(const VD (&xi)[dim], VD (&N)[1 << dim])
    {
      VD w[dim][2];
      for (int d = 0; d < dim; ++d)
        w[d][0] = 1 - xi[d], w[d][1] = xi[d];
      for (unsigned int a = 0; a < (1u << dim); ++a)
        {
          const unsigned int b0 = a & 1, b1 = (a >> 1) & 1;
          if constexpr (dim == 2)
            N[a] = w[0][b0] * w[1][b1];
          else
            N[a] = w[0][b0] * (w[1][b1] * w[2][(a >> 2) & 1]);
        }
    }

    /// Turns the values f[a] at the 2^dim corners of a cell (corner a: bit
    /// d set for the upper node in direction d) into the coefficients of
    /// their multilinear interpolant in monomial form, f(xi) = sum_S c[S]
    /// prod_{d in S} xi_d (S a set of directions as a bit mask): per
    /// direction d, c[S + d] -= c[S]. Sum N_a f_a and sum f_a grad N_a of
    /// the points of a cell then cost a few multiply-adds per point on
    /// coefficients shared by the cell (instead of 2^dim (dim + 1) per
    /// value); the same polynomial, so the results agree up to round-off.
    template <int dim, typename VD>
    [[gnu::always_inline]] inline void
    monomial_coefficients(VD (&c)[1 << dim])
    {
      for (int d = 0; d < dim; ++d)
        for (unsigned int a = 0; a < (1u << dim); ++a)
          if ((a >> d) & 1)
            c[a] -= c[a ^ (1u << d)];
    }

    /// Value and gradient (with respect to xi) at xi of the multilinear
    /// polynomial with monomial coefficients @p c (Horner form).
    template <int dim, typename VD>
    [[gnu::always_inline]] inline void
    multilinear(const VD (&c)[1 << dim],
                const VD (&xi)[dim],
                VD &val,
                VD (&grad)[dim])
    {
      const VD x = xi[0], y = xi[1];
      if constexpr (dim == 2)
        {
          const VD b = c[2] + c[3] * x;
          val        = (c[0] + c[1] * x) + y * b;
          grad[0]    = c[1] + c[3] * y;
          grad[1]    = b;
        }
      else
        {
          const VD z = xi[2];
          const VD b = c[2] + c[3] * x, e = c[4] + c[5] * x,
                   f = c[6] + c[7] * x;
          const VD t = e + y * f;
          val        = ((c[0] + c[1] * x) + y * b) + z * t;
          grad[0]    = (c[1] + c[3] * y) + z * (c[5] + c[7] * y);
          grad[1]    = b + z * f;
          grad[2]    = t;
        }
    }

    /// 1 in the first @p nl lanes, 0 in the others.
    template <typename VD>
    inline VD
    lane_mask(const unsigned int nl)
    {
      VD r = {};
      for (unsigned int l = 0; l < nl; ++l)
        r[l] = 1.;
      return r;
    }

    /// Software prefetch of the cache line that holds point @p q of each
    /// array (rw 0: to read, 1: to write). The loops stream about 30 point
    /// arrays at once, more than the hardware prefetchers follow.
    template <int rw, typename Array>
    [[gnu::always_inline]] inline void
    prefetch(const Array &a, const std::size_t q)
    {
      __builtin_prefetch(a.data() + q, rw, 3);
    }
    template <int rw, typename Array, std::size_t k>
    [[gnu::always_inline]] inline void
    prefetch(const std::array<Array, k> &a, const std::size_t q)
    {
      for (const auto &c : a)
        __builtin_prefetch(c.data() + q, rw, 3);
    }
    /// Points ahead of the block at which the loops prefetch: 2 cache lines
    /// of doubles per array (measured on the benchmark: 16 points gave
    /// 94 ns per APIC point-step, 32 points 99, 64 points 114, none 114).
    constexpr std::size_t prefetch_distance = 16;

    /// Stores the first @p nl lanes of @p r at a[p0], a[p0 + 1], ...
    template <typename VD>
    inline void
    simd_store(std::vector<double> &a,
               const std::size_t    p0,
               const unsigned int   nl,
               const VD             r)
    {
      if (nl == simd_width<VD>)
        std::memcpy(&a[p0], &r, sizeof(r));
      else
        for (unsigned int l = 0; l < nl; ++l)
          a[p0 + l] = r[l];
    }

    /// The sums (x0 + x1) + (x2 + x3) of the lanes of @p c[0..3], as the
    /// four lanes of one value; for 8 lanes, the sums ((x0 + x1) + (x2 +
    /// x3)) + ((x4 + x5) + (x6 + x7)) of the lanes of @p c[0..7] (the
    /// grouping that two 4-lane blocks summed in turn give).
    template <typename VD>
    [[gnu::always_inline]] inline VD
    lane_sums(const VD *c)
    {
      if constexpr (simd_width<VD> == 4)
        {
          typedef long long index __attribute__((vector_size(32)));
          const VD ab = __builtin_shuffle(c[0], c[1], index{0, 4, 2, 6}) +
                        __builtin_shuffle(c[0], c[1], index{1, 5, 3, 7});
          const VD cd = __builtin_shuffle(c[2], c[3], index{0, 4, 2, 6}) +
                        __builtin_shuffle(c[2], c[3], index{1, 5, 3, 7});
          return __builtin_shuffle(ab, cd, index{0, 1, 4, 5}) +
                 __builtin_shuffle(ab, cd, index{2, 3, 6, 7});
        }
      else
        {
          static_assert(simd_width<VD> == 8, "4 or 8 lanes");
          typedef long long index __attribute__((vector_size(64)));
          // Pairs of neighbouring lanes, then pairs of pairs (each half),
          // then the two halves.
          VD p[4];
          for (unsigned int k = 0; k < 4; ++k)
            p[k] = __builtin_shuffle(c[2 * k],
                                     c[2 * k + 1],
                                     index{0, 8, 2, 10, 4, 12, 6, 14}) +
                   __builtin_shuffle(c[2 * k],
                                     c[2 * k + 1],
                                     index{1, 9, 3, 11, 5, 13, 7, 15});
          const VD q0 =
            __builtin_shuffle(p[0], p[1], index{0, 1, 8, 9, 4, 5, 12, 13}) +
            __builtin_shuffle(p[0], p[1], index{2, 3, 10, 11, 6, 7, 14, 15});
          const VD q1 =
            __builtin_shuffle(p[2], p[3], index{0, 1, 8, 9, 4, 5, 12, 13}) +
            __builtin_shuffle(p[2], p[3], index{2, 3, 10, 11, 6, 7, 14, 15});
          return __builtin_shuffle(q0, q1, index{0, 1, 2, 3, 8, 9, 10, 11}) +
                 __builtin_shuffle(q0, q1, index{4, 5, 6, 7, 12, 13, 14, 15});
        }
    }

    /// Adds the contributions @p c (n values per corner, one point per
    /// lane) of blocks of points to the corner nodes: fields[k][node0[l] +
    /// offset[a]] += c[a][k][l]. When the four points of a block lie in the
    /// same cell (the usual case: points are sorted by cell) the lanes are
    /// summed first ((c0 + c1) + (c2 + c3)), and the lane sums of
    /// consecutive one-cell blocks of the same cell (the points
    /// are sorted by cell: 2 x 2 x 2 points per cell are two blocks) are
    /// kept in @p acc and added to the nodes once per cell (flush()), every
    /// node value of the cell written once. The sum per node then groups the
    /// cell's points ((c0 + c1) + (c2 + c3)) + ((c4 + c5) + (c6 + c7)): a
    /// round-off-level reordering. Mixed blocks go lane by lane in point
    /// order.
    template <std::size_t n_corners, std::size_t n, unsigned int W>
    struct CellScatter
    {
      using VD = typename SimdOf<W>::type;
      static_assert((n_corners * n) % W == 0, "groups of W");
      static constexpr unsigned int n_groups = n_corners * n / W;
      static constexpr std::size_t  none     = std::size_t(-1);

      CellScatter(const std::array<std::ptrdiff_t, n_corners> &offset,
                  double *const                               *fields)
          : offset(offset)
          , fields(fields)
      {
      }
      ~CellScatter()
      {
        flush();
      }

      [[gnu::always_inline]] inline void
      add(const VD (&c)[n_corners][n],
          const std::size_t (&node0)[W],
          const unsigned int nl)
      {
        if (nl == W && one_cell(node0))
          {
            const VD *cf = &c[0][0];
            if (node0[0] == cell0)
              for (unsigned int g = 0; g < n_groups; ++g)
                acc[g] += lane_sums(cf + W * g);
            else
              {
                flush();
                cell0 = node0[0];
                for (unsigned int g = 0; g < n_groups; ++g)
                  acc[g] = lane_sums(cf + W * g);
              }
          }
        else
          {
            flush();
            for (unsigned int l = 0; l < nl; ++l)
              for (unsigned int a = 0; a < n_corners; ++a)
                {
                  const std::size_t I = node0[l] + offset[a];
                  for (unsigned int k = 0; k < n; ++k)
                    fields[k][I] += c[a][k][l];
                }
          }
      }
      void
      flush()
      {
        if (cell0 == none)
          return;
        double s[n_corners * n];
        std::memcpy(s, acc, sizeof(s));
        for (unsigned int a = 0; a < n_corners; ++a)
          {
            const std::size_t I = cell0 + offset[a];
            for (unsigned int k = 0; k < n; ++k)
              fields[k][I] += s[n * a + k];
          }
        cell0 = none;
      }

      const std::array<std::ptrdiff_t, n_corners> &offset;
      double *const                               *fields; ///< n node arrays
      std::size_t                                  cell0 = none;
      VD                                           acc[n_groups];
    };

    /// P2G contributions of a block of points (one per lane) to its corner
    /// nodes (eqs. 11-13): per corner a, c[a] = {m N, m N v_p(x_I) (dim),
    /// g m_true N - V (sigma + q I) grad N (dim)}. @p s: stress {xx yy zz
    /// xy xz yz}; A (APIC): v_p(x_I) = v_p + C_p (x_I - x_p) with
    /// x_I - x_p = h (b - xi), FLIP: v_p. G (the light-node mass floor):
    /// also c[a][1 + 2 dim] = m h |grad N_a| sum_b h |grad N_b|, the
    /// point's part of the row sum of the corner's stiffness over c^2.
    /// B (Solid/Volumetric strain rate = centroid): the in-plane mean
    /// normal stress p = tr(sigma + q I) / dim (the dim in-plane normal
    /// components) acts through the tent gradients @p dNc at the volume
    /// centroid of the cell's points, the deviator sigma + q I - p I
    /// through those at the point: the transpose of the strain rate of
    /// stress_block() (B-bar), so that the nodal forces' power is the
    /// stress power of the points. With G the stiffness row of a corner
    /// then also holds the pressure's part, m h |dNc_a| sum_b h |dNc_b|
    /// (a bound: each part with the P-wave modulus). Without B @p dNc is
    /// not read.
    template <bool         A,
              bool         G,
              bool         B,
              int          dim,
              unsigned int n_corners,
              typename VD>
    [[gnu::always_inline]] inline void
    p2g_block(const VD (&xi)[dim],
              const VD (&N)[n_corners],
              const VD (&dN)[n_corners][dim],
              const VD (&dNc)[n_corners][dim],
              const VD m,
              const VD mg,
              const VD V,
              const VD q,
              const VD (&s)[6],
              const VD (&v)[dim],
              const VD (&C)[dim * dim],
              const double          h,
              const Tensor<1, dim> &gravity,
              VD (&c)[n_corners][1 + 2 * dim + G])
    {
      VD Vs[dim][dim], g[dim], v0[dim], Ch[dim][dim];
      for (int i = 0; i < dim; ++i)
        {
          for (int j = 0; j < dim; ++j)
            Vs[i][j] = V * s[sidx(i, j)];
          Vs[i][i] += V * q;
          g[i]  = mg * gravity[i];
          v0[i] = v[i];
          for (int j = 0; j < dim; ++j)
            Ch[i][j] = VD{};
        }
      // B-bar: V p at the centroid, V (sigma + q I - p I) at the point.
      VD Vp = {};
      if constexpr (B)
        {
          for (int i = 0; i < dim; ++i)
            Vp += Vs[i][i];
          Vp *= 1. / dim;
          for (int i = 0; i < dim; ++i)
            Vs[i][i] -= Vp;
        }
      if constexpr (A)
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j)
            {
              Ch[i][j] = h * C[i * dim + j];
              v0[i] -= Ch[i][j] * xi[j];
            }
      for (unsigned int a = 0; a < n_corners; ++a)
        {
          const VD mN = m * N[a];
          c[a][0]     = mN;
          for (int i = 0; i < dim; ++i)
            {
              VD va = v0[i];
              for (int j = 0; j < dim; ++j)
                if ((a >> j) & 1)
                  va += Ch[i][j];
              VD f = g[i] * N[a];
              for (int j = 0; j < dim; ++j)
                f -= Vs[i][j] * dN[a][j];
              if constexpr (B)
                f -= Vp * dNc[a][i];
              c[a][1 + i]       = mN * va;
              c[a][1 + dim + i] = f;
            }
        }
      if constexpr (G)
        {
          VD g_norm[n_corners], sum = {};
          for (unsigned int a = 0; a < n_corners; ++a)
            {
              VD g2 = {};
              for (int j = 0; j < dim; ++j)
                g2 += dN[a][j] * dN[a][j];
              g_norm[a] = h * simd_sqrt(g2);
              sum += g_norm[a];
            }
          const VD ms = m * sum;
          for (unsigned int a = 0; a < n_corners; ++a)
            c[a][1 + 2 * dim] = ms * g_norm[a];
          if constexpr (B)
            {
              VD gc_norm[n_corners], sum_c = {};
              for (unsigned int a = 0; a < n_corners; ++a)
                {
                  VD g2 = {};
                  for (int j = 0; j < dim; ++j)
                    g2 += dNc[a][j] * dNc[a][j];
                  gc_norm[a] = h * simd_sqrt(g2);
                  sum_c += gc_norm[a];
                }
              const VD ms_c = m * sum_c;
              for (unsigned int a = 0; a < n_corners; ++a)
                c[a][1 + 2 * dim] += ms_c * gc_norm[a];
            }
        }
    }

    /// The point arrays that the P2G reads (see SolidMPM).
    template <int dim>
    struct P2GInput
    {
      const std::array<std::vector<double>, dim>       &x, &corner, &v;
      const std::array<std::vector<double>, dim * dim> &C;
      const std::vector<double>                &true_mass, &volume, &visc;
      const std::array<std::vector<double>, 6> &sigma;
      const std::vector<std::uint32_t>         &node0;
      const double                              scaling, h;
      const Tensor<1, dim>                     &gravity;
      /// B only: the points' cells and the local coordinates of the
      /// volume centroid of each cell's points (SolidMPM::cell_centroid).
      const std::vector<std::uint32_t>           &cell;
      const std::array<std::vector<double>, dim> &centroid;
    };

    /// The local coordinates @p xc of the volume centroid of the cells of
    /// the points of block @p b (first nodes @p n0): one cell's broadcast
    /// when the points share it, else lane by lane.
    template <int dim, unsigned int W, typename VD>
    [[gnu::always_inline]] inline void
    block_centroid(const std::array<std::vector<double>, dim> &centroid,
                   const std::vector<std::uint32_t>           &cell,
                   const PointBlock<W>                        &b,
                   const std::size_t (&n0)[W],
                   VD (&xc)[dim])
    {
      if (one_cell(n0))
        {
          const auto c = cell[b.pl[0]];
          for (int d = 0; d < dim; ++d)
            xc[d] = VD{} + centroid[d][c];
        }
      else
        for (unsigned int l = 0; l < W; ++l)
          {
            const auto c = cell[b.pl[l]];
            for (int d = 0; d < dim; ++d)
              xc[d][l] = centroid[d][c];
          }
    }

    /// P2G (eqs. 11-13) of the blocks of points starting at p0 = b, b +
    /// W, ... < e (of n points) into @p out: the contributions of
    /// a block in SIMD (p2g_block), then added to the nodes (CellScatter).
    /// Not inlined: update_stresses() calls it for chunks of points that it
    /// just updated (still in the L1 cache), and the two loop bodies
    /// compiled apart keep their values in registers.
    template <bool A, bool G, bool B, int dim, std::size_t n_corners>
    [[gnu::noinline]] void
    p2g_blocks(const P2GInput<dim>                                       &in,
               const std::size_t                                          b,
               const std::size_t                                          e,
               const std::size_t                                          n,
               CellScatter<n_corners, 1 + 2 * dim + G, point_lanes<dim>> &out)
    {
      constexpr unsigned int W = point_lanes<dim>;
      using VD                 = typename SimdOf<W>::type;
      const double ih          = 1. / in.h;
      for (std::size_t p0 = b; p0 < e; p0 += W)
        {
          const PointBlock<W> blk(p0, n);
          const bool          full = blk.full;
          const auto         &pl   = blk.pl;
          VD                  xi[dim], N[n_corners], dN[n_corners][dim];
          block_tents<dim>(in.x, in.corner, blk, ih, xi, N, dN);
          std::size_t n0[W];
          for (unsigned int l = 0; l < W; ++l)
            n0[l] = in.node0[pl[l]];
          // B: the tent gradients at the cell's centroid (else unused).
          VD dNc[n_corners][dim];
          if constexpr (B)
            {
              VD xc[dim], Nc[n_corners];
              block_centroid<dim>(in.centroid, in.cell, blk, n0, xc);
              tents<dim>(xc, ih, Nc, dNc);
            }
          const VD mg = simd_load(in.true_mass, pl, full), m = mg * in.scaling;
          VD       sp[6], vp[dim], Cp[dim * dim];
          for (unsigned int c = 0; c < 6; ++c)
            sp[c] = simd_load(in.sigma[c], pl, full);
          for (int i = 0; i < dim; ++i)
            vp[i] = simd_load(in.v[i], pl, full);
          if constexpr (A)
            for (unsigned int c = 0; c < dim * dim; ++c)
              Cp[c] = simd_load(in.C[c], pl, full);
          // Per corner: mass, momentum (dim), force (dim) (, stiffness).
          VD c[n_corners][1 + 2 * dim + G];
          p2g_block<A, G, B>(xi,
                             N,
                             dN,
                             B ? dNc : dN,
                             m,
                             mg,
                             simd_load(in.volume, pl, full),
                             simd_load(in.visc, pl, full),
                             sp,
                             vp,
                             Cp,
                             in.h,
                             in.gravity,
                             c);
          out.add(c, n0, blk.nl);
        }
    }
    /// APIC: adds point p's affine velocity term C_p : C_p D_p of the
    /// kinetic energy to v2 (D_p per direction h^2 xi (1 - xi), xi the
    /// position in the cell that the next P2G uses).
    template <int dim>
    inline void
    add_affine_kinetic(const std::array<std::vector<double>, dim>       &x,
                       const std::array<std::vector<double>, dim>       &corner,
                       const std::array<std::vector<double>, dim * dim> &C,
                       const std::size_t                                 p,
                       const double                                      h,
                       double                                           &v2)
    {
      const double ih = 1. / h;
      for (int j = 0; j < dim; ++j)
        {
          const double xi = (x[j][p] - corner[j][p]) * ih;
          const double D  = h * h * xi * (1 - xi);
          for (int i = 0; i < dim; ++i)
            v2 += C[i * dim + j][p] * C[i * dim + j][p] * D;
        }
    }

    /// The velocity gradient times dt of the points of a block, L dt =
    /// sum v_a (x) grad N_a dt, the gradient of the interpolant of the nodal
    /// velocities @p vel in monomial form (as in g2p()): nodal values
    /// loaded once and broadcast when the W points lie in the same cell (the
    /// usual case: the points are sorted by cell), their coefficients @p cv
    /// shared by the blocks of the cell (@p coef_cell: the cell whose
    /// coefficients @p cv holds, none (-1) after a block of several cells).
    template <int dim, std::size_t W, typename VD>
    [[gnu::always_inline]] inline void
    block_velocity_gradient(
      const double *const                           *vel,
      const std::array<std::ptrdiff_t, (1u << dim)> &corner_offset,
      const std::size_t (&n0)[W],
      const VD (&xi)[dim],
      const double dt_ih,
      VD (&cv)[dim][1u << dim],
      std::size_t &coef_cell,
      VD (&L)[3][3])
    {
      auto coefficients = [&](auto &&nodal) {
        for (int i = 0; i < dim; ++i)
          {
            for (unsigned int a = 0; a < (1u << dim); ++a)
              cv[i][a] = nodal(vel[i], corner_offset[a]);
            monomial_coefficients<dim>(cv[i]);
          }
      };
      corner_coefficients<VD>(n0, coef_cell, coefficients);
      for (int i = 0; i < dim; ++i)
        {
          VD val, g[dim];
          multilinear<dim>(cv[i], xi, val, g);
          for (int j = 0; j < dim; ++j)
            L[i][j] = dt_ih * g[j];
        }
    }

    /// E(T_new), E(T_old) and sigma_y(T_new) of the cell last looked up.
    struct CellModuli
    {
      unsigned int cell;
      double       E, E_old, sy;
    };

    /// E(T_new), E(T_old), sigma_y(T_new) and the temperatures of the
    /// points of a block into @p sb and @p sy: the points are sorted by
    /// cell, so the tables are read once per cell run (@p cache; kernel and
    /// viscous pressure share E); one-cell blocks broadcast the cell's
    /// values.
    template <std::size_t W, typename VD>
    [[gnu::always_inline]] inline void
    block_moduli(const SolidMaterial              &mat,
                 const std::vector<std::uint32_t> &cell,
                 const std::size_t (&pl)[W],
                 const std::size_t (&n0)[W],
                 const std::vector<double> &T_old,
                 const std::vector<double> &T_new,
                 CellModuli                &cache,
                 StressBlockOf<VD>         &sb,
                 VD                        &sy)
    {
      if (one_cell(n0))
        {
          const auto cp = cell[pl[0]];
          if (cp != cache.cell)
            cache.cell = cp, cache.E = mat.youngs_modulus.value(T_new[cp]),
            cache.E_old = mat.youngs_modulus.value(T_old[cp]),
            cache.sy    = mat.yield_stress.value(T_new[cp]);
          sb.E     = VD{} + cache.E;
          sb.E_old = VD{} + cache.E_old;
          sb.T_old = VD{} + T_old[cp];
          sb.T_new = VD{} + T_new[cp];
          sy       = VD{} + cache.sy;
        }
      else
        for (unsigned int l = 0; l < W; ++l)
          {
            const auto cp = cell[pl[l]];
            if (cp != cache.cell)
              cache.cell = cp, cache.E = mat.youngs_modulus.value(T_new[cp]),
              cache.E_old = mat.youngs_modulus.value(T_old[cp]),
              cache.sy    = mat.yield_stress.value(T_new[cp]);
            sb.E[l]     = cache.E;
            sb.E_old[l] = cache.E_old;
            sb.T_old[l] = T_old[cp];
            sb.T_new[l] = T_new[cp];
            sy[l]       = cache.sy;
          }
    }

    /// Kinetic energy and momentum of the points of a block in SIMD, when
    /// every point stays in its cell (the usual case; the sums are taken
    /// lane by lane in point order, the arithmetic per point that of
    /// SolidMPM::finish_points()): false (nothing added) otherwise.
    template <int dim, bool A, typename VD>
    [[gnu::always_inline]] inline bool
    block_kinetic_in_cell(const VD (&vp)[dim],
                          const VD (&xn)[dim],
                          const VD (&cn)[dim],
                          const VD (&Cp)[dim * dim],
                          const double h,
                          const double ih,
                          const VD     use,
                          const VD     m,
                          const VD     mg,
                          VD          &kinetic_v,
                          VD (&momentum_v)[dim])
    {
      auto in_cell = xn[0] >= cn[0] && xn[0] <= cn[0] + h;
      for (int d = 1; d < dim; ++d)
        in_cell = in_cell && xn[d] >= cn[d] && xn[d] <= cn[d] + h;
      bool all_in = true;
      for (unsigned int l = 0; l < simd_width<VD>; ++l)
        all_in = all_in && in_cell[l];
      if (!all_in)
        return false;
      VD v2 = {};
      for (int d = 0; d < dim; ++d)
        v2 += vp[d] * vp[d];
      if constexpr (A)
        for (int j = 0; j < dim; ++j)
          {
            const VD xj = (xn[j] - cn[j]) * ih;
            const VD D  = h * h * xj * (1 - xj);
            for (int i = 0; i < dim; ++i)
              v2 += Cp[i * dim + j] * Cp[i * dim + j] * D;
          }
      kinetic_v += use * (0.5 * m * v2);
      for (int d = 0; d < dim; ++d)
        momentum_v[d] += use * (mg * vp[d]);
      return true;
    }

    /// The point arrays of SolidMPM that the block loops of g2p() and
    /// update_stresses() read and write.
    template <int dim>
    struct PointArrays
    {
      std::array<std::vector<double>, dim>       &x, &corner, &v, &xdot;
      std::array<std::vector<double>, dim * dim> &C;
      std::vector<double>                        &true_mass, &volume, &visc;
      std::array<std::vector<double>, 6>         &sigma;
      std::vector<double>                        &eps_p;
      const std::vector<std::uint32_t>           &cell, &node0;
    };

    /// The constants of one update_stresses() step: nodal velocities
    /// @p vel, temperatures, time step, cell size and the viscous pressure
    /// q = b1 h sqrt(M m / V) tr(D) / dt with M = E M_per_E.
    template <int dim>
    struct StressStep
    {
      const SolidMaterial                           &mat;
      const double *const                           *vel;
      const std::array<std::ptrdiff_t, (1u << dim)> &corner_offset;
      const std::vector<double>                     &T_old, &T_new;
      const double dt, h, ih, dt_ih, b1, b1h, M_per_E, idt, scaling;
      /// B only: the local coordinates of the volume centroid of each
      /// cell's points (SolidMPM::cell_centroid).
      const std::array<std::vector<double>, dim> &centroid;
    };

    /// The constants of an update_stresses() step of @p dt with cell size
    /// @p h: M_per_E = (1 - nu) / ((1 + nu) (1 - 2 nu)) (M = E M_per_E, the
    /// P-wave modulus) and b1 the bulk viscosity of the viscous pressure.
    template <int dim>
    StressStep<dim>
    stress_step(const SolidMaterial                           &mat,
                const double *const                           *vel,
                const std::array<std::ptrdiff_t, (1u << dim)> &corner_offset,
                const std::vector<double>                     &T_old,
                const std::vector<double>                     &T_new,
                const double                                   dt,
                const double                                   h,
                const double                                   scaling,
                const std::array<std::vector<double>, dim>    &centroid)
    {
      const double b1 = mat.bulk_viscosity, ih = 1. / h;
      const double nu      = mat.poisson_ratio;
      const double M_per_E = (1 - nu) / ((1 + nu) * (1 - 2 * nu));
      const double b1h = b1 * h, idt = 1. / dt;
      return {mat,
              vel,
              corner_offset,
              T_old,
              T_new,
              dt,
              h,
              ih,
              dt * ih,
              b1,
              b1h,
              M_per_E,
              idt,
              scaling,
              centroid};
    }

    /// The moduli of the cell of the first of @p n points (none: zero), to
    /// start the cache of block_moduli().
    inline CellModuli
    first_cell_moduli(const SolidMaterial              &mat,
                      const std::vector<std::uint32_t> &cell,
                      const std::size_t                 n,
                      const std::vector<double>        &T_old,
                      const std::vector<double>        &T_new)
    {
      const unsigned int E_cell = cell.empty() ? 0 : cell[0];
      return {E_cell,
              n > 0 ? mat.youngs_modulus.value(T_new[E_cell]) : 0.,
              n > 0 ? mat.youngs_modulus.value(T_old[E_cell]) : 0.,
              n > 0 ? mat.yield_stress.value(T_new[E_cell]) : 0.};
    }

    /// Software prefetch for the block of update_stresses() at @p p0 (of
    /// @p n points): the arrays of point p0 + prefetch_distance.
    template <int dim, bool A>
    [[gnu::always_inline]] inline void
    prefetch_stress_block(const PointArrays<dim> &pa,
                          const std::size_t       p0,
                          const std::size_t       n)
    {
      if (p0 % 8 == 0 && p0 + prefetch_distance < n)
        {
          const std::size_t q = p0 + prefetch_distance;
          prefetch<1>(pa.x, q), prefetch<0>(pa.corner, q);
          prefetch<1>(pa.sigma, q), prefetch<1>(pa.eps_p, q);
          prefetch<1>(pa.volume, q), prefetch<1>(pa.visc, q);
          prefetch<0>(pa.true_mass, q), prefetch<0>(pa.v, q);
          if (q % 16 == 0)
            prefetch<0>(pa.node0, q), prefetch<0>(pa.cell, q);
          if constexpr (A)
            prefetch<0>(pa.C, q);
          else
            prefetch<0>(pa.xdot, q);
        }
    }

    /// Constitutive update of the points of block @p blk (at @p p0) of
    /// update_stresses(): velocity gradient L dt (block_velocity_gradient(),
    /// with the shared @p coef_cell and @p cv), stress and plastic strain
    /// (update_stress_block(), stored), the stress work and the work of the
    /// viscous pressure of the step added to @p work_v, the new viscous
    /// pressure and volume stored, the smallest new volume of the lanes
    /// into @p vmin. Returns in @p use the mask of the lanes in use and in
    /// @p m, @p mg the inertial and true masses. B (Solid/Volumetric
    /// strain rate = centroid): the trace of L dt is that at the volume
    /// centroid of the cell's points, the difference to the point's added
    /// in equal parts to the dim in-plane normal components (the
    /// deviatoric part stays the point's; plane strain keeps L_zz = 0).
    template <int dim, bool B, unsigned int W, typename VD>
    [[gnu::always_inline]] inline void
    stress_block(const StressStep<dim> &st,
                 PointArrays<dim>      &pa,
                 const PointBlock<W>   &blk,
                 const std::size_t      p0,
                 std::size_t           &coef_cell,
                 VD (&cv)[dim][1u << dim],
                 CellModuli &moduli,
                 VD         &work_v,
                 VD         &vmin,
                 VD         &use,
                 VD         &m,
                 VD         &mg)
    {
      constexpr unsigned int n_stress = 6;
      const unsigned int     nl       = blk.nl;
      const bool             full     = blk.full;
      const auto            &pl       = blk.pl;
      VD                     xi[dim];
      block_xi<dim>(pa.x, pa.corner, blk, st.ih, xi);
      StressBlockOf<VD> sb;
      VD(&L)[3][3] = sb.L;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          L[i][j] = VD{};
      std::size_t n0[W];
      for (unsigned int l = 0; l < W; ++l)
        n0[l] = pa.node0[pl[l]];
      block_velocity_gradient<dim>(
        st.vel, st.corner_offset, n0, xi, st.dt_ih, cv, coef_cell, L);
      if constexpr (B)
        {
          VD centre[dim];
          block_centroid<dim>(st.centroid, pa.cell, blk, n0, centre);
          VD div_c = {}, div_p = {};
          for (int i = 0; i < dim; ++i)
            {
              VD val, g[dim];
              multilinear<dim>(cv[i], centre, val, g);
              div_c += g[i];
              div_p += L[i][i];
            }
          const VD shift = (st.dt_ih * div_c - div_p) * (1. / dim);
          for (int i = 0; i < dim; ++i)
            L[i][i] += shift;
        }
      VD s_old[n_stress];
      for (unsigned int c = 0; c < n_stress; ++c)
        sb.s[c] = s_old[c] = simd_load(pa.sigma[c], pl, full);
      sb.eps_p = simd_load(pa.eps_p, pl, full);
      VD sy;
      block_moduli(st.mat, pa.cell, pl, n0, st.T_old, st.T_new, moduli, sb, sy);
      update_stress_block(st.mat, sb, sy);
      for (unsigned int c = 0; c < n_stress; ++c)
        simd_store(pa.sigma[c], p0, nl, sb.s[c]);
      simd_store(pa.eps_p, p0, nl, sb.eps_p);
      // Stress work of the step, sum (sigma_old + sigma_new)/2 : D dt
      // (in-plane components; plane strain has no zz strain).
      VD w = {}, trL = {};
      for (int i = 0; i < dim; ++i)
        {
          trL += L[i][i];
          for (int j = 0; j < dim; ++j)
            w += (s_old[sidx(i, j)] + sb.s[sidx(i, j)]) * L[i][j];
        }
      // Viscous pressure of the forces of this step, then the new one.
      const VD V = simd_load(pa.volume, pl, full);
      mg         = simd_load(pa.true_mass, pl, full);
      m          = mg * st.scaling;
      VD q       = simd_load(pa.visc, pl, full);
      use        = full ? VD{} + 1. : lane_mask<VD>(nl);
      work_v += use * (0.5 * V * w + V * q * trL);
      if (st.b1 > 0)
        {
          q = st.b1h * simd_sqrt(sb.E * st.M_per_E * m / V) * trL * st.idt;
          simd_store(pa.visc, p0, nl, q);
        }
      const VD V_new = V * (1 + trL);
      simd_store(pa.volume, p0, nl, V_new);
      // Volume check (the spare lanes of a partial block repeat a point).
      vmin = V_new < vmin ? V_new : vmin;
    }

    /// Moves the points of block @p blk (at @p p0) of update_stresses()
    /// with the grid velocity of the step (APIC: that is the point
    /// velocity), then their kinetic energy and momentum and the cell check
    /// (block_kinetic_in_cell()): false when a point left its cell (nothing
    /// added; SolidMPM::finish_points() then takes the block).
    template <int dim, bool A, unsigned int W, typename VD>
    [[gnu::always_inline]] inline bool
    move_block(const StressStep<dim> &st,
               PointArrays<dim>      &pa,
               const PointBlock<W>   &blk,
               const std::size_t      p0,
               const VD               use,
               const VD               m,
               const VD               mg,
               VD                    &kinetic_v,
               VD (&momentum_v)[dim])
    {
      const unsigned int nl   = blk.nl;
      const bool         full = blk.full;
      const auto        &pl   = blk.pl;
      VD                 vp[dim], xn[dim], cn[dim];
      for (int d = 0; d < dim; ++d)
        {
          vp[d] = simd_load(pa.v[d], pl, full);
          xn[d] = simd_load(pa.x[d], pl, full) +
                  st.dt * (A ? vp[d] : simd_load(pa.xdot[d], pl, full));
          simd_store(pa.x[d], p0, nl, xn[d]);
          cn[d] = simd_load(pa.corner[d], pl, full);
        }
      VD Cp[dim * dim];
      if constexpr (A)
        for (unsigned int c = 0; c < dim * dim; ++c)
          Cp[c] = simd_load(pa.C[c], pl, full);
      // Kinetic energy and momentum, the cell check: in SIMD when every
      // point stays in its cell, else point by point.
      return block_kinetic_in_cell<dim, A>(
        vp, xn, cn, Cp, st.h, st.ih, use, m, mg, kinetic_v, momentum_v);
    }

    /// Software prefetch for the block of g2p() at @p p0 (of @p n points):
    /// the arrays of point p0 + prefetch_distance.
    template <int dim, bool A>
    [[gnu::always_inline]] inline void
    prefetch_g2p_block(const PointArrays<dim> &pa,
                       const std::size_t       p0,
                       const std::size_t       n)
    {
      if (p0 % 8 == 0 && p0 + prefetch_distance < n)
        {
          const std::size_t q = p0 + prefetch_distance;
          prefetch<0>(pa.x, q), prefetch<0>(pa.corner, q);
          prefetch<0>(pa.true_mass, q);
          if (q % 16 == 0)
            prefetch<0>(pa.node0, q);
          if constexpr (A)
            prefetch<1>(pa.C, q), prefetch<1>(pa.v, q);
          else
            prefetch<0>(pa.v, q), prefetch<1>(pa.xdot, q);
        }
    }

    /// Monomial coefficients @p cv of the nodal velocities @p vel (and
    /// FLIP, !A: @p ca of the nodal accelerations @p acc) of the cells of
    /// the block with first nodes @p n0, for g2p(): one load and a
    /// broadcast when the points lie in the same cell (the usual case: the
    /// points are sorted by cell), turned into monomial coefficients once
    /// per cell (@p coef_cell: the cell whose coefficients @p cv, @p ca
    /// hold, none (-1) after a block of several cells); mixed blocks gather
    /// lane by lane (the same coefficients per lane).
    template <int dim, bool A, std::size_t W, typename VD>
    [[gnu::always_inline]] inline void
    g2p_coefficients(
      const double *const                           *vel,
      const double *const                           *acc,
      const std::array<std::ptrdiff_t, (1u << dim)> &corner_offset,
      const std::size_t (&n0)[W],
      VD (&cv)[dim][1u << dim],
      VD (&ca)[dim][1u << dim],
      std::size_t &coef_cell)
    {
      constexpr unsigned int n_corners    = 1u << dim;
      auto                   coefficients = [&](auto &&nodal) {
        for (int i = 0; i < dim; ++i)
          {
            for (unsigned int a = 0; a < n_corners; ++a)
              {
                cv[i][a] = nodal(vel[i], corner_offset[a]);
                if constexpr (!A)
                  ca[i][a] = nodal(acc[i], corner_offset[a]);
              }
            monomial_coefficients<dim>(cv[i]);
            if constexpr (!A)
              monomial_coefficients<dim>(ca[i]);
          }
      };
      corner_coefficients<VD>(n0, coef_cell, coefficients);
    }

    /// New velocity of the points of block @p blk (at @p p0) of g2p() at
    /// their local coordinates @p xi, from the coefficients @p cv (@p ca)
    /// of their cells: v_g = sum N_a v_a, C = sum v_a (x) grad N_a (the
    /// gradient of the interpolant), FLIP: a_g = sum N_a a_a. APIC: v =
    /// v_g and C into @p Cn (stored by remap_momentum()); FLIP: v += dt a_g
    /// and the grid velocity v_g stored in xdot (it moves the point at the
    /// end of the step, update_stresses()). The new v is stored and
    /// returned in @p vp.
    template <int dim, bool A, unsigned int W, typename VD>
    [[gnu::always_inline]] inline void
    g2p_velocity(PointArrays<dim>    &pa,
                 const PointBlock<W> &blk,
                 const std::size_t    p0,
                 const VD (&xi)[dim],
                 const VD (&cv)[dim][1u << dim],
                 const VD (&ca)[dim][1u << dim],
                 const double ih,
                 const double dt,
                 VD (&vp)[dim],
                 VD (&Cn)[dim][dim])
    {
      VD vg[dim], ag[dim];
      for (int i = 0; i < dim; ++i)
        {
          VD g[dim];
          multilinear<dim>(cv[i], xi, vg[i], g);
          if constexpr (A)
            for (int j = 0; j < dim; ++j)
              Cn[i][j] = ih * g[j];
          else
            multilinear<dim>(ca[i], xi, ag[i], g);
        }
      for (int i = 0; i < dim; ++i)
        {
          vp[i] = A ? vg[i] : simd_load(pa.v[i], blk.pl, blk.full) + dt * ag[i];
          simd_store(pa.v[i], p0, blk.nl, vp[i]);
          if constexpr (!A)
            simd_store(pa.xdot[i], p0, blk.nl, vg[i]);
        }
    }

    /// Re-map (MUSL) of the new momentum of the points of block @p blk (at
    /// @p p0) of g2p() with the weights @p N of the step (those of the
    /// P2G, so that the re-mapped nodal velocity of a node is a mean of
    /// point velocities with the node mass): the contributions m N_a
    /// v_p(x_a) to the corners into @p nmom, with (APIC) v_p(x_a) = v_p +
    /// C_p (x_a - x_p), C_p = @p Cn stored; FLIP: v_p.
    template <int dim, bool A, unsigned int W, typename VD>
    [[gnu::always_inline]] inline void
    remap_momentum(PointArrays<dim>    &pa,
                   const PointBlock<W> &blk,
                   const std::size_t    p0,
                   const VD (&xi)[dim],
                   const VD (&N)[1u << dim],
                   const VD (&vp)[dim],
                   const VD (&Cn)[dim][dim],
                   const double h,
                   const double scaling,
                   VD (&nmom)[1u << dim][dim])
    {
      const VD m = simd_load(pa.true_mass, blk.pl, blk.full) * scaling;
      VD       v0[dim], Ch[dim][dim];
      for (int i = 0; i < dim; ++i)
        v0[i] = vp[i];
      if constexpr (A)
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j)
            {
              simd_store(pa.C[i * dim + j], p0, blk.nl, Cn[i][j]);
              Ch[i][j] = h * Cn[i][j];
              v0[i] -= Ch[i][j] * xi[j];
            }
      for (unsigned int a = 0; a < (1u << dim); ++a)
        {
          const VD mN = m * N[a];
          for (int i = 0; i < dim; ++i)
            {
              VD va = v0[i];
              if constexpr (A)
                for (int j = 0; j < dim; ++j)
                  if ((a >> j) & 1)
                    va += Ch[i][j];
              nmom[a][i] = mN * va;
            }
        }
    }
  } // namespace mpm_kernels
} // namespace femp

#endif
