// femp: explicit MPM for the fusible solid, MUSL variant with FLIP or APIC
// velocity transfer (paper eqs. 11-13; see solid_mpm.h for the algorithm,
// the choice of variant and the cell-crossing rules).
#include <deal.II/base/mpi.h>

#include <femp/grid/cell_state.h>
#include <femp/solid/solid_mpm.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace femp
{
  namespace
  {
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
    template <bool A, bool G, int dim, unsigned int n_corners, typename VD>
    [[gnu::always_inline]] inline void
    p2g_block(const VD (&xi)[dim],
              const VD (&N)[n_corners],
              const VD (&dN)[n_corners][dim],
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
    };

    /// P2G (eqs. 11-13) of the blocks of points starting at p0 = b, b +
    /// W, ... < e (of n points) into @p out: the contributions of
    /// a block in SIMD (p2g_block), then added to the nodes (CellScatter).
    /// Not inlined: update_stresses() calls it for chunks of points that it
    /// just updated (still in the L1 cache), and the two loop bodies
    /// compiled apart keep their values in registers.
    template <bool A, bool G, int dim, std::size_t n_corners>
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
          p2g_block<A, G>(xi,
                          N,
                          dN,
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
          std::size_t n0[W];
          for (unsigned int l = 0; l < W; ++l)
            n0[l] = in.node0[pl[l]];
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
                const double                                   scaling)
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
              scaling};
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
    /// @p m, @p mg the inertial and true masses.
    template <int dim, unsigned int W, typename VD>
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
  } // namespace

  template <int dim>
  SolidMPM<dim>::SolidMPM(const BackgroundGrid<dim> &grid,
                          const SolidMaterial       &material,
                          MaterialPoints<dim>       &points)
      : grid(grid)
      , mat(material)
      , points(points)
      , apic(material.velocity_transfer ==
             SolidMaterial::VelocityTransfer::apic)
  {
    const auto &s = grid.node_strides();
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        corner_offset[a] = 0;
        for (int d = 0; d < dim; ++d)
          if (a & (1u << d))
            corner_offset[a] += s[d];
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::gather(const std::vector<std::uint8_t> &excluded_cell,
                        const double                     mass_scaling,
                        const bool                       same_members)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    const bool apic_now =
      mat.velocity_transfer == SolidMaterial::VelocityTransfer::apic;
    AssertThrow(points.n_properties() >= P::n_used(true, apic_now),
                ExcMessage("SolidMPM: the material points do not carry the "
                           "solid (or APIC) properties"));
    // The same members in the same pool slots and order as at the last
    // gather: nobody but write_back() has changed their state since (the
    // flow writes fluid points only, the temperature step their state,
    // which exchange_since_gather() checked), so the arrays are kept.
    const bool keep = same_members && gathered && apic_now == apic &&
                      excluded_cell == excluded && aside_changed.empty() &&
                      points.layout_unchanged(gathered_layout, cell);
    // Otherwise, the same handler layout (no re-sort or re-index): only the
    // cells whose points changed are read again.
    const bool merge =
      !keep && gathered && apic_now == apic && excluded_cell == excluded &&
      points.layout_mark().generation == gathered_layout.generation;
    apic = apic_now;
    if (!gathered || excluded_cell != excluded)
      {
        excluded = excluded_cell;
        set_exchange_cells();
      }
    scaling = mass_scaling;
    ++gathers;
    gather_aside_n = gather_aside_k = 0;
    left_cells.clear();
    // The P2G buffer of the fused pass: zero again, and its node list anew.
    clear_next();
    next_ready         = false;
    steps_since_gather = 0;
    for (const auto n : next_nodes)
      node_mark[n] = 0;
    next_nodes.clear();
    node_mark.resize(grid.n_local_nodes(), 0);
    for (const auto c : reached_cells)
      cell_mark[c] = 0;
    reached_cells.clear();
    cell_mark.resize(grid.n_local(), 0);
    if (keep)
      ++gathers_kept;
    else if (merge)
      {
        ++gathers_merged;
        merge_members();
#ifdef DEBUG
        // Debug builds: the merge must give what a full copy gives.
        {
          const auto xs = x, vs = v, cs = corner, ss = sigma;
          const auto Cs = C;
          const auto m = true_mass, vo = volume, vi = visc, e = eps_p;
          const auto ce = cell, no = node0;
          const auto ha = handle, mi = member_id;
          copy_members();
          Assert(xs == x && vs == v && cs == corner && Cs == C && ss == sigma &&
                   m == true_mass && vo == volume && vi == visc && e == eps_p &&
                   ce == cell && no == node0 && ha == handle && mi == member_id,
                 ExcMessage("the merged gather differs from a full copy"));
        }
#endif
      }
    else
      copy_members();
    for (const auto c : aside_changed)
      aside_changed_mark[c] = 0;
    aside_changed.clear();
    left_rank_points.clear();
    gathered        = true;
    gathered_layout = points.layout_mark();
    moved_cell = lost = false;
    left_rank         = 0;
    for (std::size_t p = 0; p < node0.size(); ++p)
      if (p == 0 || node0[p] != node0[p - 1])
        mark_cell_nodes(cell[p], node0[p]);
    sum_energies();
  }

  template <int dim>
  void
  SolidMPM<dim>::find_members(
    const std::size_t                                    c,
    std::vector<std::pair<unsigned int, std::uint32_t>> &out)
  {
    using P         = typename MaterialPoints<dim>::PropertyIndex;
    auto      &pool = points.particle_handler_for_update().get_property_pool();
    const auto handles           = points.cell_point_handles(c);
    const std::size_t     n_cell = handles.size();
    constexpr std::size_t ahead  = 16;
    // No stress, hardening memory, viscous pressure or affine velocity
    // (and, with @p velocity, no velocity): a point that left the solid.
    const auto clear_solid_state = [this](const ArrayView<double> &q,
                                          const bool               velocity) {
      for (unsigned int k = P::stress; k < P::stress + dim * (dim + 1) / 2; ++k)
        q[k] = 0;
      if (velocity)
        for (int d = 0; d < dim; ++d)
          q[P::velocity + d] = 0;
      q[P::plastic_strain]   = 0;
      q[P::viscous_pressure] = 0;
      if constexpr (dim == 2)
        q[P::stress_zz] = 0;
      if (apic)
        for (unsigned int k = 0; k < dim * dim; ++k)
          q[P::affine_velocity + k] = 0;
    };
    for (std::size_t i = 0; i < n_cell; ++i)
      {
        if (i + ahead < n_cell)
          {
            const auto hn = handles[i + ahead];
            __builtin_prefetch(pool.get_properties(hn).data() + P::state, 1);
            __builtin_prefetch(&pool.get_location(hn), 0);
          }
        const auto              hp = handles[i];
        const ArrayView<double> q  = pool.get_properties(hp);
        if (q[P::state] == MaterialPoints<dim>::fluid)
          {
            // Melted: no stress, no hardening memory, no momentum (without
            // the melt flow a melted point is at rest; its kinetic energy
            // was booked as removed by melting), so that it solidifies
            // again stress-free and at rest (doc/solid.md "Melting and
            // re-solidification"). With the flow, its velocity is the
            // flow's (doc/solid.md "Flow and solid together").
            clear_solid_state(q, !flow_owns_fluid);
          }
        if (q[P::state] != MaterialPoints<dim>::solid)
          continue;
        const auto idx = grid.local_index(grid.cell_of(pool.get_location(hp)));
        if (excluded[idx])
          continue;
        if (set_aside(idx))
          {
            // A detached drop (set_aside_cells()): at rest and
            // stress-free, out of the solid. A point still moving was
            // carried in by the solid since the last gather (points set
            // aside before are at rest): counted, with its kinetic
            // energy (inertial mass, APIC affine part), for resort().
            double v2 = 0;
            for (int d = 0; d < dim; ++d)
              v2 += q[P::velocity + d] * q[P::velocity + d];
            if (apic)
              {
                const auto  &xp  = pool.get_location(hp);
                const auto   ijk = grid.global_index(idx);
                const double h   = grid.h();
                for (int j = 0; j < dim; ++j)
                  {
                    const double xi = (xp[j] - grid.origin()[j]) / h - ijk[j];
                    for (int i = 0; i < dim; ++i)
                      v2 += q[P::affine_velocity + i * dim + j] *
                            q[P::affine_velocity + i * dim + j] * h * h * xi *
                            (1 - xi);
                  }
              }
            if (v2 > 0)
              gather_aside_n += 1,
                gather_aside_k += 0.5 * q[P::mass] * scaling * v2;
            clear_solid_state(q, true);
            continue;
          }
        out.emplace_back(hp, idx);
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::set_aside_cells(const std::vector<std::uint32_t> &cells)
  {
    if (cells == aside_cells)
      return;
    if (aside.empty())
      {
        aside.assign(grid.n_local(), 0);
        aside_changed_mark.assign(grid.n_local(), 0);
      }
    const auto mark = [this](const std::uint32_t c) {
      if (!aside_changed_mark[c])
        aside_changed_mark[c] = 1, aside_changed.push_back(c);
    };
    for (const auto c : aside_cells)
      aside[c] = 0, mark(c);
    for (const auto c : cells)
      aside[c] = 1, mark(c);
    aside_cells = cells;
  }

  template <int dim>
  void
  SolidMPM<dim>::read_member(const std::size_t   p,
                             const unsigned int  hp,
                             const std::uint32_t idx)
  {
    using P    = typename MaterialPoints<dim>::PropertyIndex;
    auto &pool = points.particle_handler_for_update().get_property_pool();
    const ArrayView<const double> q   = pool.get_properties(hp);
    const Point<dim>             &xp  = pool.get_location(hp);
    const auto                    ijk = grid.global_index(idx);
    handle[p]                         = hp;
    cell[p]                           = idx;
    for (int d = 0; d < dim; ++d)
      {
        corner[d][p] = grid.origin()[d] + ijk[d] * grid.h();
        x[d][p]      = xp[d];
        v[d][p]      = q[P::velocity + d];
      }
    if (apic)
      for (unsigned int c = 0; c < dim * dim; ++c)
        C[c][p] = q[P::affine_velocity + c];
    true_mass[p] = q[P::mass];
    volume[p]    = q[P::volume];
    visc[p]      = q[P::viscous_pressure];
    node0[p]     = grid.first_node_of_cell(idx);
    if constexpr (dim == 2)
      {
        sigma[0][p] = q[P::stress + 0];
        sigma[1][p] = q[P::stress + 1];
        sigma[2][p] = q[P::stress_zz];
        sigma[3][p] = q[P::stress + 2];
        sigma[4][p] = 0.;
        sigma[5][p] = 0.;
      }
    else
      for (unsigned int c = 0; c < n_stress; ++c) // same order
        sigma[c][p] = q[P::stress + c];
    eps_p[p]      = q[P::plastic_strain];
    const auto id = pool.get_id(hp);
    member_id[p]  = id;
    if (id / 64 >= member_bits.size())
      member_bits.resize(id / 64 + 1, 0);
    member_bits[id / 64] |= std::uint64_t(1) << (id % 64);
  }

  namespace
  {
    /// Resizes every per-point array of @p arrays to @p n (the arrays
    /// filled by index: no zero fill needed, but resize() does it).
    template <typename... V>
    void
    resize_all(const std::size_t n, V &...arrays)
    {
      (arrays.resize(n), ...);
    }
  } // namespace

  template <int dim>
  void
  SolidMPM<dim>::copy_members()
  {
    // Cell by cell in increasing flat index, from MaterialPoints' per-cell
    // cache of pool handles, but the FE zone's deeper cells (neither
    // members nor fluid there, see exchange_cell): a first pass finds the
    // points that take part (pool handle, cell), the second copies their
    // state into the arrays, with prefetches ahead.
    const auto &occupied = points.occupied_cells();
    found.clear();
    found.reserve(points.particle_handler().n_locally_owned_particles());
    for (std::size_t c = 0; c < occupied.size(); ++c)
      if (exchange_cell.empty() || exchange_cell[occupied[c].first])
        find_members(c, found);
    const std::size_t n = found.size();
    for (int d = 0; d < dim; ++d)
      resize_all(n, x[d], v[d], corner[d]);
    for (auto &c : C)
      c.resize(apic ? n : 0);
    for (auto &s : sigma)
      s.resize(n);
    resize_all(
      n, true_mass, volume, visc, eps_p, cell, node0, handle, member_id);
    // Membership by particle id, for exchange_since_gather().
    member_bits.assign(
      points.particle_handler().get_next_free_particle_index() / 64 + 1, 0);
    auto &pool = points.particle_handler_for_update().get_property_pool();
    constexpr std::size_t ahead = 16;
    for (std::size_t p = 0; p < n; ++p)
      {
        if (p + ahead < n)
          {
            const auto    hn = found[p + ahead].first;
            const double *r  = pool.get_properties(hn).data();
            for (unsigned int c = 0; c < pool.n_properties_per_slot(); c += 8)
              __builtin_prefetch(r + c, 0);
            __builtin_prefetch(&pool.get_location(hn), 0);
          }
        read_member(p, found[p].first, found[p].second);
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::merge_members()
  {
    // The members of the cells whose points neither came, went nor changed
    // state since the last gather (MaterialPoints::cell_changed_since())
    // are the same points in the same order, and the arrays hold their
    // state (written back by the last scatter(); handles are stable while
    // the handler is not re-indexed): they stay, unless the cell was set
    // aside or given back since (set_aside_cells()). The changed cells are
    // looked at as copy_members() would, and both are merged in increasing
    // cell index, the order of copy_members().
    const auto &occupied = points.occupied_cells();
    found.clear();
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const auto idx = occupied[c].first;
        if ((exchange_cell.empty() || exchange_cell[idx]) &&
            changed_since_gather(idx))
          find_members(c, found);
      }
    const std::size_t n_old = handle.size();
    merge_source.clear();
    merge_source.reserve(n_old + found.size());
    // Points that left for another rank: cell[] holds the last cell they
    // crossed into on this rank, which need not be a cell the relocation
    // changed (a point that moved A -> B here and then on to the other
    // rank was removed from A, where the handler still had it).
    std::sort(left_rank_points.begin(), left_rank_points.end());
    std::size_t l = 0;
    std::size_t j = 0;
    for (std::size_t p = 0; p < n_old; ++p)
      {
        const auto idx = cell[p];
        while (l < left_rank_points.size() && left_rank_points[l] < p)
          ++l;
        const bool left =
          l < left_rank_points.size() && left_rank_points[l] == p;
        if (left || changed_since_gather(idx))
          {
            // Dropped: read again below if still a member here.
            member_bits[member_id[p] / 64] &=
              ~(std::uint64_t(1) << (member_id[p] % 64));
            continue;
          }
        while (j < found.size() && found[j].second < idx)
          merge_source.push_back(~std::int64_t(j++));
        merge_source.push_back(std::int64_t(p));
      }
    while (j < found.size())
      merge_source.push_back(~std::int64_t(j++));
    const std::size_t n = merge_source.size();
    // The kept entries as runs of consecutive entries (most of them: only
    // the changed cells break them), copied run by run.
    struct Run
    {
      std::size_t to, from, length;
    };
    std::vector<Run> runs;
    for (std::size_t k = 0; k < n; ++k)
      if (merge_source[k] >= 0)
        {
          const auto from = static_cast<std::size_t>(merge_source[k]);
          if (!runs.empty() && runs.back().to + runs.back().length == k &&
              runs.back().from + runs.back().length == from)
            ++runs.back().length;
          else
            runs.push_back({k, from, 1});
        }
    // Field by field: the kept entries move to their new places.
    auto move_field = [&](auto &field) {
      using T   = typename std::decay_t<decltype(field)>::value_type;
      auto &out = [&]() -> std::vector<T> & {
        if constexpr (std::is_same_v<T, double>)
          return merge_buffer_double;
        else if constexpr (std::is_same_v<T, std::uint32_t>)
          return merge_buffer_u32;
        else
          return merge_buffer_index;
      }();
      out.resize(n);
      for (const auto &r : runs)
        std::copy(field.begin() + r.from,
                  field.begin() + r.from + r.length,
                  out.begin() + r.to);
      field.swap(out);
    };
    for (int d = 0; d < dim; ++d)
      move_field(x[d]), move_field(v[d]), move_field(corner[d]);
    if (apic)
      for (auto &c : C)
        move_field(c);
    for (auto &s : sigma)
      move_field(s);
    move_field(true_mass), move_field(volume), move_field(visc);
    move_field(eps_p), move_field(cell), move_field(node0);
    move_field(handle), move_field(member_id);
    for (std::size_t k = 0; k < n; ++k)
      if (merge_source[k] < 0)
        {
          const auto &f = found[~merge_source[k]];
          read_member(k, f.first, f.second);
        }
  }

  template <int dim>
  void
  SolidMPM<dim>::set_exchange_cells()
  {
    // Outside the FE zone, and the zone's cells with a neighbour (faces,
    // edges, corners) outside it or beyond the local box.
    exchange_cell.assign(grid.n_local(), 1);
    if (excluded.size() != grid.n_local())
      return;
    for (std::size_t idx = 0; idx < grid.n_local(); ++idx)
      {
        if (!excluded[idx])
          continue;
        const auto ijk  = grid.global_index(idx);
        bool       near = false;
        for (unsigned int k = 0; k < std::pow(3u, dim) && !near; ++k)
          {
            auto         nb = ijk;
            unsigned int r  = k;
            for (int d = 0; d < dim; ++d, r /= 3)
              nb[d] += int(r % 3) - 1;
            near = !grid.in_box(nb) || !excluded[grid.local_index(nb)];
          }
        exchange_cell[idx] = near;
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::mark_cell_nodes(const std::size_t idx, const std::size_t n0)
  {
    if (!cell_mark[idx])
      cell_mark[idx] = 1, reached_cells.push_back(idx);
    for (unsigned int a = 0; a < n_corners; ++a)
      {
        const std::size_t n = n0 + corner_offset[a];
        if (!node_mark[n])
          node_mark[n] = 1, next_nodes.push_back(n);
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::clear_next()
  {
    if (next_dirty)
      for (auto &f : next)
        if (!f.empty()) // the stiffness rows: with the floor only
          for (const auto n : next_nodes)
            f[n] = 0;
    next_dirty = false;
  }

  template <int dim>
  typename SolidMPM<dim>::Exchange
  SolidMPM<dim>::exchange_since_gather() const
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    Exchange   e;
    const auto h = grid.h(), ih = 1. / h;
    // Over the points of the cells outside the FE zone and its first
    // layer (exchange_cell; the zone's deeper points are solid, below the
    // solidus by the zone's guard, and never members), cell by cell from
    // MaterialPoints' cache, prefetching state and position.
    // At a gather every point is a member exactly when it is solid and
    // outside the excluded cells (a kept gather: the exchange found no
    // point for which this failed). A cell whose points neither changed
    // state nor came or went since (MaterialPoints::cell_changed_since())
    // keeps that, so only the others are looked at: in the cooling a few
    // cells where points solidify or members crossed a face, not every
    // point of the powder and the MPM zone.
    auto                 &pool = points.particle_handler().get_property_pool();
    const auto           &occupied = points.occupied_cells();
    constexpr std::size_t ahead    = 16;
    for (std::size_t c = 0; c < occupied.size(); ++c)
      {
        const auto idx = occupied[c].first;
        if (!exchange_cell.empty() && !exchange_cell[idx])
          continue;
        if (gathered && !changed_since_gather(idx))
          continue;
        const auto        handles = points.cell_point_handles(c);
        const std::size_t n_cell  = handles.size();
        for (std::size_t i = 0; i < n_cell; ++i)
          {
            if (i + ahead < n_cell)
              {
                const auto hn = handles[i + ahead];
                __builtin_prefetch(pool.get_properties(hn).data() + P::state,
                                   0);
                __builtin_prefetch(&pool.get_location(hn), 0);
              }
            const auto                    hp     = handles[i];
            const ArrayView<const double> q      = pool.get_properties(hp);
            const bool                    member = is_member(pool.get_id(hp));
            const bool solid = q[P::state] == MaterialPoints<dim>::solid;
            if (!member &&
                !solid) // (neither before nor now: the cell does not matter)
              continue;
            const Point<dim> xp   = pool.get_location(hp);
            const auto       ijk  = grid.cell_of(xp);
            const auto       cidx = grid.local_index(ijk);
            const bool       out  = excluded[cidx];
            const bool       away = set_aside(cidx);
            if (member == (solid && !out && !away))
              continue;
            if (member && solid && out) // now in a cell of the FE zone
              {
                if (e.n_lost == 0)
                  e.lost_at = xp;
                e.n_lost += 1;
                continue;
              }
            // Kinetic energy as the points had it in (or bring it to) the
            // solid: inertial mass, APIC affine part with the tents of the
            // cell.
            double v2 = 0;
            for (int d = 0; d < dim; ++d)
              v2 += q[P::velocity + d] * q[P::velocity + d];
            if (apic)
              for (int j = 0; j < dim; ++j)
                {
                  const double xi = (xp[j] - grid.origin()[j]) * ih - ijk[j];
                  const double D  = h * h * xi * (1 - xi);
                  for (int i = 0; i < dim; ++i)
                    v2 += q[P::affine_velocity + i * dim + j] *
                          q[P::affine_velocity + i * dim + j] * D;
                }
            const double k = 0.5 * q[P::mass] * scaling * v2;
            if (member && solid) // now in a detached drop
              e.n_set_aside += 1, e.k_set_aside += k;
            else if (member)
              e.n_melted += 1, e.k_melted += k;
            else
              e.n_solidified += 1, e.k_solidified += k;
          }
      }
    return e;
  }

  template <int dim>
  void
  SolidMPM<dim>::write_back()
  {
    using P    = typename MaterialPoints<dim>::PropertyIndex;
    auto &pool = points.particle_handler_for_update().get_property_pool();
    const std::size_t     n     = true_mass.size();
    constexpr std::size_t ahead = 8;
    for (std::size_t p = 0; p < n; ++p)
      {
        if (p + ahead < n) // the pool slots written a few points ahead
          {
            const auto hn = handle[p + ahead];
            double    *r  = pool.get_properties(hn).data();
            for (unsigned int c = 0; c < pool.n_properties_per_slot(); c += 8)
              __builtin_prefetch(r + c, 1);
            __builtin_prefetch(&pool.get_location(hn), 1);
          }
        const auto              hp = handle[p];
        const ArrayView<double> q  = pool.get_properties(hp);
        Point<dim>              xp;
        for (int d = 0; d < dim; ++d)
          {
            xp[d]              = x[d][p];
            q[P::velocity + d] = v[d][p];
          }
        pool.set_location(hp, xp);
        if constexpr (dim == 2)
          {
            q[P::stress + 0] = sigma[0][p];
            q[P::stress + 1] = sigma[1][p];
            q[P::stress + 2] = sigma[3][p];
            q[P::stress_zz]  = sigma[2][p];
          }
        else
          for (unsigned int c = 0; c < n_stress; ++c)
            q[P::stress + c] = sigma[c][p];
        if (apic)
          for (unsigned int c = 0; c < dim * dim; ++c)
            q[P::affine_velocity + c] = C[c][p];
        q[P::plastic_strain]   = eps_p[p];
        q[P::volume]           = volume[p];
        q[P::viscous_pressure] = visc[p];
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::scatter()
  {
    write_back();
    // Points that changed cells: move them in the handler, to the owner
    // where the new cell is a ghost cell (cell by cell, looking only in the
    // cells they left; deal.II's global sort only if that fails).
    if (Utilities::MPI::logical_or(moved_cell, grid.communicator()))
      {
        std::sort(left_cells.begin(), left_cells.end());
        left_cells.erase(std::unique(left_cells.begin(), left_cells.end()),
                         left_cells.end());
        if (!points.relocate_points(&left_cells))
          points.points_moved();
      }
    left_cells.clear();
    moved_cell = false;
  }

  template <int dim>
  void
  SolidMPM<dim>::resort()
  {
    // Points that entered a cell of a neighbour rank go there with the
    // others that changed cells (scatter(): only the cells they left are
    // looked at, their new cells are ghost cells here; deal.II's global sort
    // of every point, about 500 ns per point, only if that fails). Then
    // gather again: the members of this rank changed.
    scatter();
    const std::vector<std::uint8_t> mask = excluded;
    gather(mask, scaling);
  }

  template <int dim>
  void
  SolidMPM<dim>::sum_energies()
  {
    const double h = grid.h();
    kinetic        = 0;
    weight_momentum.fill(0.);
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            v2 += v[d][p] * v[d][p];
            weight_momentum[d] += true_mass[p] * v[d][p];
          }
        if (apic)
          add_affine_kinetic<dim>(x, corner, C, p, h, v2);
        kinetic += 0.5 * (true_mass[p] * scaling) * v2;
      }
  }

  template <int dim>
  void
  SolidMPM<dim>::p2g(SolidNodeFields<dim> &nodes, const Tensor<1, dim> &gravity)
  {
    // Mass, momentum (dim), force (dim) and, with the light-node mass
    // floor, the stiffness row sums.
    const unsigned int nf = 1 + 2 * dim + (stiffness_rows ? 1 : 0);
    double            *nodes_out[2 + 2 * dim] = {nodes.mass.data()};
    for (int d = 0; d < dim; ++d)
      nodes_out[1 + d]                     = nodes.momentum[d].data(),
                    nodes_out[1 + dim + d] = nodes.force[d].data();
    if (stiffness_rows)
      {
        AssertDimension(nodes.stiffness.size(), nodes.mass.size());
        nodes_out[1 + 2 * dim] = nodes.stiffness.data();
      }
    // Sums of the fused pass of the last update_stresses(): add them (the
    // caller zeroed the nodes; a plain copy would not do for nodes it did
    // not zero) and leave the buffer zero.
    if (next_ready && gravity == p2g_gravity)
      {
        for (unsigned int k = 0; k < nf; ++k)
          {
            double *const out = nodes_out[k];
            double *const buf = next[k].data();
            for (const auto I : next_nodes)
              out[I] += buf[I], buf[I] = 0;
          }
        next_ready = next_dirty = false;
        return;
      }
    clear_next();
    next_ready   = false;
    have_gravity = true;
    p2g_gravity  = gravity;

    const std::size_t   n = true_mass.size();
    const P2GInput<dim> in{x,
                           corner,
                           v,
                           C,
                           true_mass,
                           volume,
                           visc,
                           sigma,
                           node0,
                           scaling,
                           grid.h(),
                           gravity};
    // The transfer and the floor are compile-time constants inside the
    // loop (measured: 7-20 % faster than a run-time branch per point).
    auto run = [&](auto transfer, auto floor) {
      constexpr bool A = decltype(transfer)::value;
      constexpr bool G = decltype(floor)::value;
      CellScatter<n_corners, 1 + 2 * dim + G, point_lanes<dim>> out(
        corner_offset, nodes_out);
      p2g_blocks<A, G>(in, 0, n, n, out);
    };
    if (apic && stiffness_rows)
      run(std::true_type(), std::true_type());
    else if (apic)
      run(std::true_type(), std::false_type());
    else if (stiffness_rows)
      run(std::false_type(), std::true_type());
    else
      run(std::false_type(), std::false_type());
  }

  template <int dim>
  void
  SolidMPM<dim>::set_stiffness_rows(const bool on)
  {
    // The fused buffer of the next P2G was summed with or without them.
    clear_next();
    next_ready     = false;
    stiffness_rows = on;
  }

  template <int dim>
  void
  SolidMPM<dim>::g2p(SolidNodeFields<dim> &nodes, const double dt)
  {
    const double  h = grid.h(), ih = 1. / h;
    const double *vel[dim], *acc[dim];
    double       *mom[dim];
    for (int d = 0; d < dim; ++d)
      {
        vel[d] = nodes.velocity[d].data();
        acc[d] = nodes.force[d].data(); // f_I / m_I at this point
        mom[d] = nodes.momentum[d].data();
      }
    const std::size_t n = true_mass.size();
    for (int d = 0; d < dim; ++d) // FLIP only (APIC: the grid velocity is v)
      xdot[d].resize(apic ? 0 : n);
    // Blocks of W points as in p2g(): nodal values gathered lane
    // by lane, the interpolation and the re-map contributions in SIMD, the
    // re-map added to the nodes in point order.
    constexpr unsigned int W = point_lanes<dim>;
    using VD                 = typename SimdOf<W>::type;
    PointArrays<dim> pa{x,
                        corner,
                        v,
                        xdot,
                        C,
                        true_mass,
                        volume,
                        visc,
                        sigma,
                        eps_p,
                        cell,
                        node0};
    // The transfer is a compile-time constant inside the loop (measured:
    // 7-20 % faster than a run-time branch per point).
    auto loop = [&](auto transfer) {
      constexpr bool                 A = decltype(transfer)::value;
      CellScatter<n_corners, dim, W> remap(corner_offset, mom);
      // Monomial coefficients of the nodal velocity (and FLIP: the nodal
      // acceleration) of the cell of the last one-cell block; the blocks
      // of a cell share them (the points are sorted by cell).
      constexpr std::size_t none      = std::size_t(-1);
      std::size_t           coef_cell = none;
      VD                    cv[dim][n_corners], ca[dim][n_corners];
      for (std::size_t p0 = 0; p0 < n; p0 += W)
        {
          const PointBlock<W> blk(p0, n);
          prefetch_g2p_block<dim, A>(pa, p0, n);
          VD xi[dim], N[n_corners];
          block_xi<dim>(pa.x, pa.corner, blk, ih, xi);
          weights<dim>(xi, N);
          std::size_t n0[W];
          for (unsigned int l = 0; l < W; ++l)
            n0[l] = pa.node0[blk.pl[l]];
          g2p_coefficients<dim, A>(
            vel, acc, corner_offset, n0, cv, ca, coef_cell);
          VD vp[dim], Cn[dim][dim];
          g2p_velocity<dim, A>(pa, blk, p0, xi, cv, ca, ih, dt, vp, Cn);
          VD nmom[n_corners][dim];
          remap_momentum<dim, A>(pa, blk, p0, xi, N, vp, Cn, h, scaling, nmom);
          remap.add(nmom, n0, blk.nl);
        }
    };
    if (apic)
      loop(std::true_type());
    else
      loop(std::false_type());
  }

  template <int dim>
  double
  SolidMPM<dim>::update_stresses(const SolidNodeFields<dim> &nodes,
                                 const double                dt,
                                 const std::vector<double>  &T_old,
                                 const std::vector<double>  &T_new)
  {
    const double  h = grid.h();
    const double *vel[dim];
    for (int d = 0; d < dim; ++d)
      vel[d] = nodes.velocity[d].data();
    double            work = 0;
    const std::size_t n    = true_mass.size();
    left_rank              = 0;
    lost                   = false;
    kinetic                = 0;
    min_volume             = std::numeric_limits<double>::infinity();
    weight_momentum.fill(0.);
    const StressStep<dim> st =
      stress_step<dim>(mat, vel, corner_offset, T_old, T_new, dt, h, scaling);
    CellModuli moduli = first_cell_moduli(mat, cell, n, T_old, T_new);
    // Fused P2G of the next step (see solid_mpm.h), into the buffer next:
    // from the second step after a gather on (the benchmark's and a coupled
    // run's sub-cycling), so that a run of one step per gather pays nothing
    // for it, nor a rank without points (no buffer). The buffer is zero
    // here (p2g() consumed or cleared it).
    const bool fuse = n > 0 && steps_since_gather > 0 && have_gravity;
    ++steps_since_gather;
    const unsigned int nf = 1 + 2 * dim + (stiffness_rows ? 1 : 0);
    double            *next_out[2 + 2 * dim] = {};
    if (fuse)
      {
        for (unsigned int k = 0; k < nf; ++k)
          {
            next[k].resize(grid.n_local_nodes(), 0.);
            next_out[k] = next[k].data();
          }
        next_dirty = true;
      }
    // Blocks of W points (point_lanes), one point per lane of a vector (GCC
    // vector extension, see constitutive.h): shape functions, velocity
    // gradient, constitutive update (update_stress_block), work, viscous
    // pressure, volume and move in SIMD; a partial last block repeats its
    // last point in the spare lanes and stores nothing from them. The sums
    // (work, kinetic energy, momentum) are taken in point order and the
    // arithmetic per point is that of the scalar formulation.
    constexpr unsigned int W = point_lanes<dim>;
    using VD                 = typename SimdOf<W>::type;
    PointArrays<dim> pa{x,
                        corner,
                        v,
                        xdot,
                        C,
                        true_mass,
                        volume,
                        visc,
                        sigma,
                        eps_p,
                        cell,
                        node0};
    auto             loop = [&](auto transfer, auto fused, auto floor) {
      constexpr bool                             A = decltype(transfer)::value;
      constexpr bool                             F = decltype(fused)::value;
      constexpr bool                             G = decltype(floor)::value;
      CellScatter<n_corners, 1 + 2 * dim + G, W> out(corner_offset, next_out);
      const P2GInput<dim>                        in{x,
                             corner,
                             v,
                             C,
                             true_mass,
                             volume,
                             visc,
                             sigma,
                             node0,
                             scaling,
                             h,
                             p2g_gravity};
      // Chunks of points: stress update and move, then (fused) the P2G of
      // the chunk's points, whose data are still in the L1 cache.
      constexpr std::size_t chunk = 16 * W;
      // Monomial coefficients of the nodal velocity of the cell of the
      // last one-cell block (see g2p()).
      constexpr std::size_t none      = std::size_t(-1);
      std::size_t           coef_cell = none;
      VD                    cv[dim][n_corners];
      // Sums of the lanes of the blocks (lanes of a partial block that
      // are not in use are masked by use); summed at the end.
      VD work_v = {}, kinetic_v = {}, momentum_v[dim] = {};
      VD vmin = VD{} + std::numeric_limits<double>::infinity();
      for (std::size_t c0 = 0; c0 < n; c0 += chunk)
        {
          const std::size_t c1 = std::min(n, c0 + chunk);
          for (std::size_t p0 = c0; p0 < c1; p0 += W)
            {
              const PointBlock<W> blk(p0, n);
              prefetch_stress_block<dim, A>(pa, p0, n);
              VD use, m, mg;
              stress_block(st,
                           pa,
                           blk,
                           p0,
                           coef_cell,
                           cv,
                           moduli,
                           work_v,
                           vmin,
                           use,
                           m,
                           mg);
              if (!move_block<dim, A>(
                    st, pa, blk, p0, use, m, mg, kinetic_v, momentum_v))
                finish_points<A>(p0, blk.nl);
            }
          if constexpr (F)
            p2g_blocks<A, G>(in, c0, c1, n, out);
        }
      work += lane_total(work_v);
      kinetic += lane_total(kinetic_v);
      for (unsigned int l = 0; l < W; ++l)
        min_volume = std::min(min_volume, vmin[l]);
      for (int d = 0; d < dim; ++d)
        weight_momentum[d] += lane_total(momentum_v[d]);
    };
    const std::true_type  yes;
    const std::false_type no;
    if (apic && fuse && stiffness_rows)
      loop(yes, yes, yes);
    else if (apic && fuse)
      loop(yes, yes, no);
    else if (apic)
      loop(yes, no, no);
    else if (fuse && stiffness_rows)
      loop(no, yes, yes);
    else if (fuse)
      loop(no, yes, no);
    else
      loop(no, no, no);
    next_ready = fuse && !lost && left_rank == 0;
    return work;
  }

  template <int dim>
  void
  SolidMPM<dim>::hold_in_domain(const std::size_t p, Point<dim> &xp)
  {
    const double h = grid.h();
    for (int d = 0; d < dim; ++d)
      {
        const double lo = grid.origin()[d];
        const double hi = lo + (grid.n_cells()[d] - 1e-6) * h;
        if (xp[d] < lo)
          {
            xp[d] = lo, v[d][p] = std::max(v[d][p], 0.);
            if (!xdot[d].empty())
              xdot[d][p] = std::max(xdot[d][p], 0.);
          }
        else if (xp[d] > hi)
          {
            xp[d] = hi, v[d][p] = std::min(v[d][p], 0.);
            if (!xdot[d].empty())
              xdot[d][p] = std::min(xdot[d][p], 0.);
          }
        x[d][p] = xp[d];
      }
    ++held;
  }

  // The points of a block of update_stresses() of which one left its cell
  // or the rank, point by point: kinetic energy and momentum, the cell
  // crossing (see solid_mpm.h) and the APIC affine part of the kinetic
  // energy with the tents of the new cell.
  template <int dim>
  template <bool A>
  void
  SolidMPM<dim>::finish_points(const std::size_t p0, const unsigned int nl)
  {
    const double h = grid.h();
    for (unsigned int l = 0; l < nl; ++l)
      {
        const std::size_t p = p0 + l;
        // Kinetic energy and momentum (APIC: the affine part is added
        // after the cell crossing, with the tents of the new cell).
        double v2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            v2 += v[d][p] * v[d][p];
            weight_momentum[d] += true_mass[p] * v[d][p];
          }

        // Cell crossing (see solid_mpm.h).
        bool inside = true;
        for (int d = 0; d < dim; ++d)
          inside =
            inside && x[d][p] >= corner[d][p] && x[d][p] <= corner[d][p] + h;
        if (!inside)
          {
            Point<dim> xp;
            for (int d = 0; d < dim; ++d)
              xp[d] = x[d][p];
            // With the melt flow, points that solidified as spatter (ejected
            // melt, moving with the fluid's velocity) can reach the domain's
            // faces; like the flow's points they are held there: put back on
            // the face, the outward velocity removed (its kinetic energy
            // leaves through the next transfer). Without the melt flow a
            // point leaving the domain stops the run.
            if (flow_owns_fluid && !grid.in_domain(xp))
              hold_in_domain(p, xp);
            const auto ijk = grid.cell_of(xp);
            if (!grid.in_domain(xp) ||
                (grid.in_box(ijk) && excluded[grid.local_index(ijk)]))
              {
                if (!lost)
                  escaped = xp;
                lost = true;
                continue;
              }
            const auto idx = grid.in_box(ijk) ? grid.local_index(ijk) : 0;
            if (!grid.in_box(ijk) ||
                grid.cell_status()[idx] != BackgroundGrid<dim>::owned)
              {
                // Its old cell, where scatter() finds it to send it to the
                // neighbour rank.
                left_cells.push_back(cell[p]);
                left_rank_points.push_back(p);
                moved_cell = true;
                ++left_rank;
                continue;
              }
            left_cells.push_back(cell[p]);
            cell[p]  = idx;
            node0[p] = grid.first_node_of_cell(idx);
            for (int d = 0; d < dim; ++d)
              corner[d][p] = grid.origin()[d] + ijk[d] * h;
            moved_cell = true;
            mark_cell_nodes(idx, node0[p]);
          }
        // APIC: affine part with the tents of the cell that now holds
        // the point (those of the next P2G). Points that left the rank
        // are counted by the gather of resort().
        if (A)
          add_affine_kinetic<dim>(x, corner, C, p, h, v2);
        kinetic += 0.5 * (true_mass[p] * scaling) * v2;
      }
  }

  template <int dim>
  double
  SolidMPM<dim>::elastic_energy(const std::vector<double> &T) const
  {
    double u = 0;
    double s[n_stress];
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        for (unsigned int c = 0; c < n_stress; ++c)
          s[c] = sigma[c][p];
        u += volume[p] * elastic_energy_density(mat, s, T[cell[p]]);
      }
    return u;
  }

  template <int dim>
  std::pair<double, unsigned int>
  SolidMPM<dim>::cell_stress_xx(const std::size_t idx) const
  {
    double       s = 0;
    unsigned int n = 0;
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      if (cell[p] == idx)
        s += sigma[0][p], ++n;
    return {n > 0 ? s / n : 0., n};
  }

  template <int dim>
  void
  SolidMPM<dim>::add_cell_fields(std::vector<std::vector<double>> &f,
                                 std::vector<double>              &count) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        SymmetricTensor<2, 3> s;
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = i; j < 3; ++j)
            s[i][j] = sigma[sidx(i, j)][p];
        for (unsigned int i = 0; i < 3; ++i)
          f[i][cell[p]] += s[i][i];
        f[3][cell[p]] += von_mises(s);
        f[4][cell[p]] += eps_p[p];
        count[cell[p]] += 1;
      }
  }

  template <int dim>
  bool
  SolidMPM<dim>::find_non_finite(Point<dim> &where) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      {
        bool bad = false;
        for (unsigned int c = 0; c < n_stress; ++c)
          bad = bad || !std::isfinite(sigma[c][p]);
        for (int d = 0; d < dim; ++d)
          bad = bad || !std::isfinite(v[d][p]) || !std::isfinite(x[d][p]);
        if (bad)
          {
            for (int d = 0; d < dim; ++d)
              where[d] = corner[d][p] + 0.5 * grid.h();
            return true;
          }
      }
    return false;
  }

  template <int dim>
  bool
  SolidMPM<dim>::find_collapsed(Point<dim> &where, double &V) const
  {
    for (std::size_t p = 0; p < true_mass.size(); ++p)
      if (!(volume[p] > 0))
        {
          for (int d = 0; d < dim; ++d)
            where[d] = x[d][p];
          V = volume[p];
          return true;
        }
    return false;
  }

  template <int dim>
  void
  SolidMPM<dim>::save_state(StateWriter &out) const
  {
    out.put(scaling);
    std::vector<std::uint64_t> ids; // sorted
    for (std::size_t w = 0; w < member_bits.size(); ++w)
      for (unsigned int b = 0; b < 64; ++b)
        if ((member_bits[w] >> b) & 1u)
          ids.push_back(64 * w + b);
    out.put_vector(ids);
    const std::size_t          n = true_mass.size();
    std::vector<std::uint64_t> keys(n);
    for (std::size_t p = 0; p < n; ++p)
      keys[p] = global_cell_number(grid, grid.global_index(cell[p]));
    out.put_vector(keys);
    for (const auto &s : sigma)
      out.put_vector(s);
    out.put_vector(eps_p);
  }

  template <int dim>
  void
  SolidMPM<dim>::load_state(std::vector<StateReader> &parts)
  {
    for (int d = 0; d < dim; ++d)
      x[d].clear(), v[d].clear(), corner[d].clear(), xdot[d].clear();
    for (auto &c : C)
      c.clear();
    for (auto &s : sigma)
      s.clear();
    true_mass.clear(), volume.clear(), visc.clear();
    eps_p.clear(), cell.clear(), node0.clear(), handle.clear();
    member_bits.clear();
    left_cells.clear();
    gathered       = false; // the next gather() copies
    const double h = grid.h();
    for (std::size_t f = 0; f < parts.size(); ++f)
      {
        StateReader &in = parts[f];
        const double s  = in.get<double>();
        if (f == 0)
          scaling = s;
        // The members of every part: the partition of the resumed run may
        // differ from the one that wrote them (another number of ranks, or
        // the same number with other cell costs), and only this rank's
        // points are ever looked up.
        const auto ids = in.get_vector<std::uint64_t>();
        for (const auto id : ids)
          {
            if (id / 64 >= member_bits.size())
              member_bits.resize(id / 64 + 1, 0);
            member_bits[id / 64] |= std::uint64_t(1) << (id % 64);
          }
        const auto keys = in.get_vector<std::uint64_t>();
        std::array<std::vector<double>, n_stress> sg;
        for (auto &c : sg)
          c = in.get_vector<double>();
        const auto ep = in.get_vector<double>();
        for (std::size_t p = 0; p < keys.size(); ++p)
          {
            const auto idx = owned_local_index(grid, keys[p]);
            if (idx < 0)
              continue;
            cell.push_back(idx);
            node0.push_back(grid.first_node_of_cell(idx));
            const auto ijk = grid.global_index(idx);
            for (int d = 0; d < dim; ++d)
              corner[d].push_back(grid.origin()[d] + ijk[d] * h);
            for (unsigned int c = 0; c < n_stress; ++c)
              sigma[c].push_back(sg[c][p]);
            eps_p.push_back(ep[p]);
          }
      }
    // Read before the next gather(): cell, stress and plastic strain; the
    // other arrays keep the common length, zero.
    const std::size_t n = cell.size();
    for (int d = 0; d < dim; ++d)
      x[d].assign(n, 0.), v[d].assign(n, 0.);
    if (apic)
      for (auto &c : C)
        c.assign(n, 0.);
    true_mass.assign(n, 0.), volume.assign(n, 0.), visc.assign(n, 0.);
    kinetic = 0;
    weight_momentum.fill(0.);
    moved_cell = lost = false;
    left_rank         = 0;
    left_rank_points.clear();
  }

  template class SolidMPM<2>;
  template class SolidMPM<3>;
} // namespace femp
