// femp: ray-traced laser absorption on the current metal surface (Fresnel
// absorption with multiple reflections; doc/absorption.md). It replaces the
// fixed absorptivity eta of the laser term q_laser of eq. (1) by the local
// Fresnel absorptivity of each ray hit, and the vertical first-surface
// deposition by deposition where the rays meet the metal.
#include <deal.II/base/mpi.h>

#include <femp/base/input_checks.h>
#include <femp/base/parameter_table.h>
#include <femp/heat/ray_traced_absorption.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

namespace femp
{
  template <int dim>
  void
  RayTracedAbsorption<dim>::Parameters::add_parameters(ParameterTable &table)
  {
    table.enter_subsection("Laser");
    table.add(
      "Absorption model",
      model,
      {{Model::fixed, "fixed"}, {Model::ray_traced, "ray traced"}},
      "'fixed': the absorbed flux is 'Absorptivity' times the beam's flux, "
      "put into the cells where the vertical beam first meets metal "
      "('Heat transfer/Laser deposition'). 'ray traced': every temperature "
      "step, rays over the beam's Gaussian profile are traced into the "
      "current metal surface (alpha = 1/2), absorbed there by the Fresnel "
      "relation of 'Refractive index' and 'Extinction coefficient' at the "
      "angle of incidence and reflected specularly (multiple reflections in "
      "a depression); each hit's absorbed power goes as a volumetric source "
      "into the surface cell next to it; the power of rays that leave the "
      "domain is booked as escaping (absorbed + escaping = P). "
      "'Absorptivity' and 'Heat transfer/Laser deposition' are then not "
      "used. Recommended where the surface is deeply depressed (normalized "
      "enthalpy above ~20-30, see the scene log and doc/absorption.md).");
    table.add("Refractive index",
              refractive_index,
              Patterns::Double(0.),
              "Real part n of the metal's complex refractive index at "
              "the laser wavelength (ray traced only), dimensionless; "
              "range (0, inf). The default is that of polished "
              "austenitic stainless steel (similar to 316) at "
              "1.064 um, room temperature (Karlsson and Ribbing, "
              "J. Appl. Phys. 53 (1982) 6340): n = 3.83, k = 5.34, "
              "normal-incidence absorptivity 0.296, matching femp's "
              "default material 316L. The material files of "
              "prm/materials set the value of their alloy "
              "(doc/absorption.md).");
    table.add("Extinction coefficient",
              extinction_coefficient,
              Patterns::Double(0.),
              "Imaginary part k of the complex refractive index at the "
              "laser wavelength (ray traced only), dimensionless; range "
              "[0, inf). Default: stainless steel at 1.064 um (see "
              "'Refractive index').");
    table.add("Rays per beam radius",
              rays_per_beam_radius,
              Patterns::Integer(1, 64),
              "Rays per 1/e^2 beam radius r_b, dimensionless: the "
              "rays start r_b / this number apart on a square lattice "
              "(3D) or a line (2D) out to 2 r_b (ray traced only); 4 "
              "gives 197 rays in 3D, 17 in 2D. Each hit's power is "
              "spread over the surface cells round it by its position, "
              "so a lattice about as fine as the cells suffices; range "
              "[1, 64].");
    table.add("Maximum reflections",
              max_reflections,
              Patterns::Integer(0, 10000),
              "After this many reflections a ray's remaining power is "
              "absorbed where it is (ray traced only); range [0, "
              "10000].");
    table.leave_subsection();
  }

  template <int dim>
  void
  RayTracedAbsorption<dim>::Parameters::declare_parameters(
    ParameterHandler &prm)
  {
    Parameters     defaults;
    ParameterTable table(prm, ParameterTable::Mode::declare);
    defaults.add_parameters(table);
  }

  template <int dim>
  void
  RayTracedAbsorption<dim>::Parameters::parse_parameters(ParameterHandler &prm)
  {
    ParameterTable table(prm, ParameterTable::Mode::parse);
    add_parameters(table);
    prm.enter_subsection("Laser");
    prm.leave_subsection();
    require(refractive_index > 0,
            "Laser/Refractive index",
            refractive_index,
            "it must be positive");
  }

  template <int dim>
  RayTracedAbsorption<dim>::RayTracedAbsorption(const Parameters          &p,
                                                const BackgroundGrid<dim> &g)
      : prm(p)
      , grid(g)
  {
  }

  template <int dim>
  double
  RayTracedAbsorption<dim>::fresnel_absorptivity(const double cos_theta) const
  {
    using C        = std::complex<double>;
    const double c = std::clamp(cos_theta, 0., 1.);
    const C      N(prm.refractive_index, prm.extinction_coefficient);
    const C      ct  = std::sqrt(1. - (1. - c * c) / (N * N));
    const C      r_s = (c - N * ct) / (c + N * ct);
    const C      r_p = (N * c - ct) / (N * c + ct);
    return 1. - 0.5 * (std::norm(r_s) + std::norm(r_p));
  }

  namespace
  {
    /// Metal fraction of a window of cells round the beam (all heights),
    /// gathered from all ranks, with multilinear interpolation.
    template <int dim>
    struct Window
    {
      const BackgroundGrid<dim> &grid;
      std::array<int, dim>       lo, size;
      std::vector<double>        a;
      double                     h;
      Point<dim>                 origin;
      std::array<int, dim>       n;
      /// Flat-index strides of the window.
      std::array<std::size_t, dim> stride;
      /// surface_cell() of each window cell, found on first use (-1: not
      /// yet): a trace asks for the same cells many times.
      mutable std::vector<signed char> surface;

      Window(const BackgroundGrid<dim> &g,
             const std::vector<double> &alpha,
             const Point<dim>          &axis,
             const double               half_width)
          : grid(g)
          , h(g.h())
          , origin(g.origin())
      {
        for (int d = 0; d < dim; ++d)
          n[d] = g.n_cells()[d];
        std::size_t total = 1;
        for (int d = 0; d < dim; ++d)
          {
            int l = 0, u = n[d] - 1;
            if (d < dim - 1)
              {
                l = std::max(
                  0,
                  int(std::floor((axis[d] - half_width - origin[d]) / h)) - 1);
                u = std::min(
                  n[d] - 1,
                  int(std::floor((axis[d] + half_width - origin[d]) / h)) + 1);
              }
            lo[d]   = l;
            size[d] = u - l + 1;
            total *= size[d];
          }
        a.assign(total, 0.);
        surface.assign(total, -1);
        stride[0] = 1;
        for (int d = 1; d < dim; ++d)
          stride[d] = stride[d - 1] * size[d - 1];
        // The owned cells of the window (not all owned cells).
        const auto &status = g.cell_status();
        for (std::size_t f = 0; f < total; ++f)
          {
            std::array<int, dim> ijk;
            std::size_t          ff = f;
            for (int d = 0; d < dim; ++d)
              {
                ijk[d] = lo[d] + int(ff % size[d]);
                ff /= size[d];
              }
            if (!g.in_box(ijk))
              continue;
            const std::size_t idx = g.local_index(ijk);
            if (status[idx] == BackgroundGrid<dim>::owned)
              a[f] = alpha[idx];
          }
        MPI_Allreduce(MPI_IN_PLACE,
                      a.data(),
                      int(a.size()),
                      MPI_DOUBLE,
                      MPI_SUM,
                      g.communicator());
      }

      bool
      contains(const std::array<int, dim> &ijk) const
      {
        for (int d = 0; d < dim; ++d)
          if (ijk[d] < lo[d] || ijk[d] >= lo[d] + size[d])
            return false;
        return true;
      }
      std::size_t
      flat(const std::array<int, dim> &ijk) const
      {
        std::size_t f = 0;
        for (int d = dim - 1; d >= 0; --d)
          f = f * size[d] + (ijk[d] - lo[d]);
        return f;
      }
      /// Cell value, extended: below the bottom and sideways by the nearest
      /// cell, above the top by gas.
      double
      cell(std::array<int, dim> ijk) const
      {
        if (ijk[dim - 1] >= n[dim - 1])
          return 0.;
        for (int d = 0; d < dim; ++d)
          ijk[d] = std::clamp(ijk[d], lo[d], lo[d] + size[d] - 1);
        return a[flat(ijk)];
      }
      double
      at(const Point<dim> &x) const
      {
        std::array<int, dim>    i0;
        std::array<double, dim> f;
        for (int d = 0; d < dim; ++d)
          {
            const double u = (x[d] - origin[d]) / h - 0.5;
            i0[d]          = int(std::floor(u));
            f[d]           = u - i0[d];
          }
        // All 2^dim cells inside the window and below its top: read them
        // directly (the same values and sum as through cell()).
        bool interior = i0[dim - 1] + 1 < n[dim - 1];
        for (int d = 0; d < dim && interior; ++d)
          interior = i0[d] >= lo[d] && i0[d] + 1 < lo[d] + size[d];
        if (interior)
          {
            const std::size_t f0 = flat(i0);
            double            v  = 0;
            for (unsigned int c = 0; c < (1u << dim); ++c)
              {
                std::size_t ff = f0;
                double      w  = 1;
                for (int d = 0; d < dim; ++d)
                  {
                    const bool up = c & (1u << d);
                    ff += up ? stride[d] : 0;
                    w *= up ? f[d] : 1 - f[d];
                  }
                if (w != 0)
                  v += w * a[ff];
              }
            return v;
          }
        double v = 0;
        for (unsigned int c = 0; c < (1u << dim); ++c)
          {
            auto   ijk = i0;
            double w   = 1;
            for (int d = 0; d < dim; ++d)
              {
                const bool up = c & (1u << d);
                ijk[d] += up;
                w *= up ? f[d] : 1 - f[d];
              }
            if (w != 0)
              v += w * cell(ijk);
          }
        return v;
      }
      /// Gradient of the interpolated field by central differences.
      Tensor<1, dim>
      gradient(const Point<dim> &x) const
      {
        Tensor<1, dim> g;
        for (int d = 0; d < dim; ++d)
          {
            Point<dim> p = x, m = x;
            p[d] += 0.5 * h;
            m[d] -= 0.5 * h;
            g[d] = (at(p) - at(m)) / h;
          }
        return g;
      }
      /// Inside the part of the window where the interpolation is exact
      /// (horizontally; the domain faces bound it where the window does).
      bool
      inside(const Point<dim> &x) const
      {
        for (int d = 0; d < dim - 1; ++d)
          {
            const double xl = origin[d] + (lo[d] == 0 ? 0. : (lo[d] + 0.5) * h);
            const double xu = origin[d] + (lo[d] + size[d] == n[d] ?
                                             n[d] * h :
                                             (lo[d] + size[d] - 0.5) * h);
            if (x[d] < xl || x[d] > xu)
              return false;
          }
        return x[dim - 1] >= origin[dim - 1];
      }
      /// Surface cell as HeatTransfer defines it (metal, non-zero central-
      /// difference gradient of alpha with zero gradient at the domain
      /// faces); cells on an inner edge of the window do not qualify.
      bool
      surface_cell(const std::array<int, dim> &ijk) const
      {
        if (!contains(ijk))
          return false;
        for (int d = 0; d < dim; ++d)
          if ((ijk[d] == lo[d] && lo[d] > 0) ||
              (ijk[d] == lo[d] + size[d] - 1 && ijk[d] < n[d] - 1))
            return false;
        const std::size_t fi = flat(ijk);
        if (surface[fi] < 0)
          surface[fi] = compute_surface_cell(ijk);
        return surface[fi] > 0;
      }
      bool
      compute_surface_cell(const std::array<int, dim> &ijk) const
      {
        if (a[flat(ijk)] <= 0)
          return false;
        double g2 = 0;
        for (int d = 0; d < dim; ++d)
          {
            auto m = ijk, p = ijk;
            m[d]           = std::max(0, ijk[d] - 1);
            p[d]           = std::min(n[d] - 1, ijk[d] + 1);
            const double g = (a[flat(p)] - a[flat(m)]) / (2 * h);
            g2 += g * g;
          }
        return std::sqrt(g2) > 1e-12 / h;
      }
    };
  } // namespace

  template <int dim>
  typename RayTracedAbsorption<dim>::Result
  RayTracedAbsorption<dim>::trace(
    const std::vector<double>                     &alpha,
    const Point<dim>                              &axis,
    const double                                   power,
    const double                                   rb,
    std::vector<std::pair<std::uint32_t, double>> &deposits) const
  {
    const Window<dim>   w(grid, alpha, axis, 3 * rb);
    const double        h     = grid.h();
    const double        z_top = w.origin[dim - 1] + w.n[dim - 1] * h;
    const double        step  = 0.25 * h;
    std::vector<double> absorbed_in(w.a.size(), 0.);
    Result              r;
    r.incident = power;

    // Rays: lattice of spacing rb/m out to 2 rb, Gaussian weights
    // normalized to the power.
    const unsigned int      m = prm.rays_per_beam_radius;
    const int               M = 2 * m;
    std::vector<Point<dim>> start;
    std::vector<double>     weight;
    double                  sum_w = 0;
    for (int i = -M; i <= M; ++i)
      for (int j = (dim == 3 ? -M : 0); j <= (dim == 3 ? M : 0); ++j)
        {
          const double x = i * rb / m, y = j * rb / m;
          const double r2 = x * x + y * y;
          if (r2 > 4 * rb * rb * (1 + 1e-12))
            continue;
          Point<dim> p = axis;
          p[0] += x;
          if (dim == 3)
            p[1] += y;
          p[dim - 1] = z_top;
          start.push_back(p);
          weight.push_back(std::exp(-2 * r2 / (rb * rb)));
          sum_w += weight.back();
        }
    r.n_rays = start.size();

    // Surface cell next to a point (a hit's, a quarter cell inside the
    // metal): among the 3^dim cells round its cell, the surface cell
    // nearest to it; -1 if none.
    auto target = [&](const Point<dim> &q) -> long {
      std::array<int, dim> c;
      for (int d = 0; d < dim; ++d)
        c[d] =
          std::clamp(int(std::floor((q[d] - w.origin[d]) / h)), 0, w.n[d] - 1);
      long                   best    = -1;
      double                 best_d2 = std::numeric_limits<double>::max();
      constexpr unsigned int n_round = dim == 3 ? 27 : 9;
      for (unsigned int o = 0; o < n_round; ++o)
        {
          auto         ijk = c;
          unsigned int oo  = o;
          for (int d = 0; d < dim; ++d, oo /= 3)
            ijk[d] += int(oo % 3) - 1;
          if (!w.surface_cell(ijk))
            continue;
          double d2 = 0;
          for (int d = 0; d < dim; ++d)
            {
              const double x = w.origin[d] + (ijk[d] + 0.5) * h - q[d];
              d2 += x * x;
            }
          if (d2 < best_d2)
            best_d2 = d2, best = long(w.flat(ijk));
        }
      return best;
    };

    // A hit's power, spread over the cells round the point q with linear
    // weights in the directions along the surface (all but the largest
    // component of the normal @p nrm), each part into the surface cell
    // nearest the centre of its column (the cell next to q where that
    // column has none): the deposited power keeps the hit's position as
    // its centre. Into one cell, it would move by up to h/2, towards the
    // beam axis for every ray of a lattice slightly finer than the cells.
    auto deposit = [&](const Point<dim>     &q,
                       const Tensor<1, dim> &nrm,
                       const long            cell,
                       const double          a) {
      int normal = 0;
      for (int d = 1; d < dim; ++d)
        if (std::abs(nrm[d]) > std::abs(nrm[normal]))
          normal = d;
      std::array<int, dim>    i0{};
      std::array<double, dim> f{};
      for (int d = 0; d < dim; ++d)
        if (d != normal)
          {
            const double u = (q[d] - w.origin[d]) / h - 0.5;
            i0[d]          = int(std::floor(u));
            f[d]           = u - i0[d];
          }
      for (unsigned int c = 0; c < (1u << dim); ++c)
        {
          if (c & (1u << normal))
            continue;
          Point<dim> qc = q;
          double     wt = 1;
          for (int d = 0; d < dim; ++d)
            if (d != normal)
              {
                const bool up = c & (1u << d);
                wt *= up ? f[d] : 1 - f[d];
                qc[d] = w.origin[d] + (i0[d] + up + 0.5) * h;
              }
          if (wt == 0)
            continue;
          const long tc = target(qc);
          absorbed_in[tc < 0 ? cell : tc] += a * wt;
        }
    };

    const double max_path = 8. * (w.n[0] + w.n[dim - 1]) * h;
    for (unsigned int ray = 0; ray < start.size(); ++ray)
      {
        double         P  = power * weight[ray] / sum_w;
        const double   P0 = P;
        Point<dim>     p  = start[ray];
        Tensor<1, dim> dir;
        dir[dim - 1] = -1;
        double path  = 0;
        for (unsigned int reflection = 0;; ++reflection)
          {
            // March to the isosurface alpha = 1/2, then bisect.
            bool       escaped = false;
            Point<dim> hit     = p;
            if (!w.inside(p))
              escaped = true;
            else if (w.at(p) < 0.5)
              for (;;)
                {
                  const Point<dim> q = p + step * dir;
                  path += step;
                  if (!w.inside(q) ||
                      (q[dim - 1] > z_top && dir[dim - 1] >= 0) ||
                      path > max_path)
                    {
                      escaped = true;
                      break;
                    }
                  if (w.at(q) >= 0.5)
                    {
                      Point<dim> a = p, b = q;
                      for (int k = 0; k < 20; ++k) // to 1e-6 of a step
                        {
                          const Point<dim> c       = 0.5 * (a + b);
                          (w.at(c) >= 0.5 ? b : a) = c;
                        }
                      hit = b;
                      break;
                    }
                  p = q;
                }
            if (escaped)
              {
                r.escaped += P;
                break;
              }
            ++r.n_hits;
            // Surface normal (out of the metal) and incidence.
            Tensor<1, dim> nrm = -w.gradient(hit);
            const double   gn  = nrm.norm();
            nrm                = gn > 1e-12 / h ? nrm / gn : -dir;
            if (dir * nrm > 0)
              nrm = -nrm;
            const double     cos_t = std::min(1., -(dir * nrm));
            const Point<dim> q     = hit - 0.25 * h * nrm;
            const long       cell  = target(q);
            if (cell < 0)
              {
                r.escaped += P; // no metal cell to take it (not expected)
                break;
              }
            const bool last = reflection >= prm.max_reflections;
            double     a    = P * fresnel_absorptivity(cos_t);
            if (last || P - a < 1e-6 * P0)
              a = P; // the small rest is absorbed here
            deposit(q, nrm, cell, a);
            r.absorbed += a;
            P -= a;
            if (P <= 0)
              break;
            // Specular reflection; step off the surface.
            dir = dir - 2 * (dir * nrm) * nrm;
            dir /= dir.norm();
            p = hit;
            for (int k = 0; k < 40 && w.at(p) >= 0.5; ++k)
              p += 0.05 * h * nrm;
          }
      }

    // Owned cells take their part.
    const auto &status = grid.cell_status();
    for (std::size_t f = 0; f < absorbed_in.size(); ++f)
      if (absorbed_in[f] > 0)
        {
          std::array<int, dim> ijk;
          std::size_t          ff = f;
          for (int d = 0; d < dim; ++d)
            {
              ijk[d] = w.lo[d] + int(ff % w.size[d]);
              ff /= w.size[d];
            }
          if (!grid.in_box(ijk))
            continue;
          const std::size_t idx = grid.local_index(ijk);
          if (status[idx] == BackgroundGrid<dim>::owned)
            deposits.emplace_back(std::uint32_t(idx), absorbed_in[f]);
        }
    return r;
  }

  template class RayTracedAbsorption<2>;
  template class RayTracedAbsorption<3>;
} // namespace femp
