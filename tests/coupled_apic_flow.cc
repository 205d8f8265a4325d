// APIC in the melt flow beside the solid (doc/flow.md "Velocity transfer",
// doc/solid.md "Flow and solid together"): tests/checkpoint_flow_solid.prm,
// a laser track over powder on a substrate with the melt flow and the solid
// (material points above a finite-element zone), run with 'Melt
// flow/Velocity transfer = APIC'.
//
// The flow carries each fluid point's affine velocity C_p in the slot that
// the solid's own APIC transfer uses; a point that solidifies enters the
// solid with C_p = 0 and the velocity the flow last gave it. In this scene
// a melted grain plunges into the substrate and one of its points
// solidifies while moving at about 3 m/s (APIC keeps the grain's momentum,
// which the default FLIP-PIC blend damps away in this coarse scene). With
// the scene's mass scaling s = 1e8 the P-wave speed of the solid,
// sqrt(M / (s rho)), is 0.57 m/s: the point moves 1.7 cells in one solid
// step and a material point collapses two steps later.
//
// Case 1, s = 1e8: the run must stop with the message that names a point
// that solidified faster than the mass-scaled wave (the cause, not the
// transfer's share of the point properties).
// Cases 2 and 3, s = 1e6 (wave speed 5.7 m/s), APIC and the default
// FLIP-PIC: the runs go through, and the solid's energy balance (external
// work, stress work, kinetic energy, the kinetic energy brought by
// solidifying points and taken by melting ones, transfer losses,
// solid_energy_ledger.h) closes within 2 % of the largest of its terms
// (measured 0.6 % with APIC, 0.8 % with FLIP-PIC); the heat balance with
// the flow's sources within 1e-4 (below 1e-5). Printed: the energies
// the solid booked, rounded.
// Case 4, s = 1e6, APIC in the flow and FLIP in the solid (which never
// writes the affine slot): every solid point that was melted must carry
// C_p = 0 at the end (the reset on solidification), and there must be
// such points. 1 and 2 ranks give the same output.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "scene_driver.h"
#include "test_tools.h"

using namespace femp_test;

namespace
{
  constexpr int dim = 2;

  /// Solid points that were melted once (peak temperature above the
  /// solidus) and those of them whose affine-velocity slot is not zero
  /// (all ranks).
  std::array<double, 2>
  resolidified_slots(const MaterialPoints<dim> &points,
                     const double               solidus,
                     MPI_Comm                   comm)
  {
    using P = typename MaterialPoints<dim>::PropertyIndex;
    std::array<double, 2> n{{0., 0.}};
    for (const auto &p : points.particle_handler())
      {
        const auto v = p.get_properties();
        if (v[P::state] != MaterialPoints<dim>::solid ||
            !(v[P::peak_temperature] > solidus))
          continue;
        n[0] += 1;
        for (unsigned int k = 0; k < dim * dim; ++k)
          if (v[P::affine_velocity + k] != 0)
            {
              n[1] += 1;
              break;
            }
      }
    Utilities::MPI::sum(ArrayView<const double>(n.data(), 2),
                        comm,
                        ArrayView<double>(n.data(), 2));
    return n;
  }

  /// run_scene() with std::cout given back also when the run throws;
  /// @p slots (if given) receives resolidified_slots() after the run.
  FempProblem<dim>::Summary
  run(const std::string           &file,
      MPI_Comm                     comm,
      const std::vector<Override> &o,
      std::array<double, 2>       *slots = nullptr)
  {
    dealii::ParameterHandler prm;
    parse_scene(prm, file, o);
    std::ofstream log("scene.log");
    struct Silence
    {
      std::streambuf *old;
      ~Silence()
      {
        std::cout.rdbuf(old);
      }
    } silence{std::cout.rdbuf(log.rdbuf())};
    FempProblem<dim> problem(prm, comm);
    problem.run();
    if (slots)
      {
        prm.enter_subsection("Material");
        const double solidus = prm.get_double("Solidus temperature");
        prm.leave_subsection();
        *slots = resolidified_slots(problem.material_points(), solidus, comm);
      }
    return problem.summary();
  }

  double
  rounded(const double x, const int digits)
  {
    if (x == 0)
      return 0;
    const double p =
      std::pow(10., digits - 1 - std::floor(std::log10(std::abs(x))));
    return std::round(x * p) / p;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  MPI_Comm                         comm = MPI_COMM_WORLD;
  Checks                           checks(comm);
  const std::string                scene = argv[1];
  const Override apic{"Melt flow", "Velocity transfer", "APIC"};
  try
    {
      // Case 1: the scene's mass scaling.
      {
        bool        stopped = false, named = false;
        std::string message;
        try
          {
            run(scene, comm, {apic});
          }
        catch (const std::exception &e)
          {
            stopped = true;
            message = e.what();
            named =
              message.find("a material point collapsed") != std::string::npos &&
              message.find("entered the solid by solidifying at") !=
                std::string::npos;
          }
        checks.in_range("APIC, s = 1e8: the run stops (1 yes)",
                        stopped ? 1. : 0.,
                        1.,
                        1.);
        checks.in_range("APIC, s = 1e8: the message names the collapse and "
                        "the point that solidified faster than the wave "
                        "(1 yes)",
                        named ? 1. : 0.,
                        1.,
                        1.);
        if (!named && Utilities::MPI::this_mpi_process(comm) == 0)
          std::cerr << message << std::endl;
      }
      // Cases 2 and 3: s = 1e6.
      const Override scaling{"Solid", "Mass scaling factor", "1e6"};
      for (const bool affine : {true, false})
        {
          const std::string c =
            affine ? "APIC, s = 1e6: " : "FLIP-PIC, s = 1e6: ";
          const auto  s = affine ? run(scene, comm, {apic, scaling}) :
                                   run(scene, comm, {scaling});
          const auto &E = s.solid_energy;
          checks.print(c + "temperature steps", s.steps, 6);
          checks.print(c + "solid steps", s.solid_steps, 6);
          checks.print(c + "kinetic energy brought by solidifying points (J/m)",
                       rounded(E.solidified, 2));
          checks.print(c + "kinetic energy taken by melting points (J/m)",
                       rounded(E.melted, 2));
          checks.print(c + "stress work (J/m)", rounded(E.internal, 2));
          const double largest =
            std::max({std::abs(E.internal), E.kinetic, E.solidified, E.melted});
          checks.at_most(c + "|solid energy balance| / its largest term",
                         std::abs(E.balance()) / largest,
                         0.02);
          const double heat =
            std::abs(s.laser + s.boundary + s.advection + s.moved_points -
                     s.losses - s.stored) /
            std::max(s.laser + std::abs(s.boundary), s.losses);
          checks.at_most(c + "heat balance error with the flow's sources, "
                             "next power of ten",
                         std::pow(10., std::ceil(std::log10(heat))),
                         1e-4);
        }
      // Case 4: APIC in the flow, FLIP in the solid, which never writes
      // the affine slot: every point that melted and solidified again
      // carries C_p = 0 at the end.
      std::array<double, 2> slots;
      run(scene,
          comm,
          {apic, scaling, {"Solid", "Velocity transfer", "FLIP"}},
          &slots);
      checks.in_range("APIC flow, FLIP solid, s = 1e6: solid points that "
                      "were melted (at least one)",
                      slots[0],
                      1.,
                      1e9);
      checks.in_range("APIC flow, FLIP solid, s = 1e6: of these, points "
                      "whose affine velocity is not zero",
                      slots[1],
                      0.,
                      0.);
    }
  catch (const std::exception &e)
    {
      std::cerr << e.what() << std::endl;
      return 1;
    }
  return checks.exit_code();
}
