// femp: SolidEnergyLedger, the energy accounts of the solid (doc/solid.md
// "Energies"; global sums, J or J/m in 2D): external work (gravity, fluid
// forces), stress work int sigma : D (internal), kinetic energy and its
// initial value, the kinetic energy lost in the MPM transfers, the kinetic
// energy of points that melted (left the solid) or solidified (entered
// it), the re-map work of MUSL and the work withheld at light nodes. The
// balance
//   W_ext - (K - K_0) - W_int - E_HG - D_transfer - K_melted + K_solidified
//   + W_remap + (mass-scaling jumps) - W_withheld
// closes to round-off for a stable solid up to the leapfrog's half-step
// term (SolidEnergies::half_step, which the energy check takes off);
// SolidSubCycle books into it after every step, gather and re-sort, and
// writes it to the energy file.
// No equation of the paper: a check of eqs. 5-17.
#ifndef femp_solid_energy_ledger_h
#define femp_solid_energy_ledger_h

#include <array>
#include <cmath>

namespace femp
{
  /// The energies of the solid at one time.
  struct SolidEnergies
  {
    double external = 0, internal = 0, kinetic = 0, hourglass = 0;
    double initial_kinetic = 0;
    /// Energy of the hourglass modes measured with the reference
    /// stiffness kappa = 0.05 even when control is off (stability studies:
    /// how large the zero-energy modes have grown).
    double hourglass_mode = 0;
    /// Kinetic energy lost in the point-grid transfers (MPM: P2G of the
    /// point momenta, incl. the projection onto the boundary conditions,
    /// and G2P; measured per step as K_points - K_grid after P2G plus
    /// K_grid - K_points after the grid update; FLIP can make it < 0).
    double transfer = 0;
    /// Kinetic energy of points that melted (left the solid) and of
    /// points that solidified (entered it), summed over the run.
    double melted = 0, solidified = 0;
    /// Work of the nodal forces on the part of the updated grid velocity
    /// that the MUSL re-map takes back, dt/2 f_I . (v_I - v_remap,I),
    /// summed over the steps: energy the MPM update creates (> 0) or
    /// destroys, a numerical error of MUSL, booked so that the balance
    /// tests the rest (doc/solid.md "Energies").
    double remap = 0;
    /// Kinetic energy created (> 0) or removed by changes of the
    /// mass-scaling factor at kept velocities (adaptive mass scaling:
    /// (s_new / s_old - 1) K at each change), summed over the run.
    double scaling_jump = 0;
    /// Work that the forces withheld at light nodes (below 'Small mass
    /// cutoff') would have done on those nodes' velocities, dt f_I . v_I
    /// summed over the steps: the stress work counts these nodes, the
    /// kinetic energy does not (< 0 when the withheld forces oppose the
    /// motion: energy the cutoff leaves in it).
    double withheld = 0;
    /// The leapfrog's half-step term, J: `kinetic` is taken at the
    /// velocities v_k after each step k (half-step velocities: the
    /// positions move by dt_k v_k), while the booked works (external work
    /// dt_k f_ext . v_k, stress work with the mean of the old and new
    /// stresses) match a kinetic energy at the whole step. Summed over the
    /// nodes (grid and FE), with P_k = v_k . f_{k+1} (f_{k+1} the force of
    /// the step after k, at the positions of step k), the balance of a
    /// linear system over steps 1..n is exactly
    ///   sum_k dt_k / 2 (P_k - P_{k-1}),
    /// the half-step term: dt/2 (P_n - P_0) at a constant step, the
    /// product form 1/2 m v_n . v_{n+1} of the whole-step kinetic energy
    /// less 1/2 m v_n^2. Each P_{k-1} is measured in step k (its old
    /// velocities and its force); for the last step, whose next force is
    /// not known yet, P_n is taken with the step's own force. Under a
    /// constant load (a body starting from rest under gravity: balance()
    /// shows 1/2 m (g dt)^2 created after the first step, a third of the
    /// check's scale) this is the balance exactly, whatever the steps; for
    /// a linear elastic body of stiffness K the balance less this term is
    /// -dt^2/2 v_n . K v_n <= 0 at a constant step. Not in balance() (the
    /// energy file keeps the half-step kinetic energy); the energy check
    /// reads whole_step_balance().
    double half_step = 0;
    double
    balance() const
    {
      return external + remap - (kinetic - initial_kinetic) - internal -
             hourglass - transfer - melted + solidified + scaling_jump -
             withheld;
    }
    /// The balance with the kinetic energy at the whole step (kinetic +
    /// half_step): round-off for a body under a constant load from rest,
    /// whatever the number of steps (doc/stability.md, "Energy check").
    double
    whole_step_balance() const
    {
      return balance() - half_step;
    }
  };

  class SolidEnergyLedger
  {
  public:
    /// Start of a run: kinetic energy @p K_total of the solid, @p K_points
    /// of its points; nothing booked.
    void
    start(const double K_total, const double K_points)
    {
      K0 = K = K_total;
      W_ext = W_int = H = H_sum = H_P = H_dt = 0;
      D_transfer = K_melted = K_solidified = W_remap = W_withheld = 0;
      K_p                                                         = K_points;
    }
    /// The global sums of one step: kinetic energy of the points
    /// @p k_points and of the FE nodes @p k_fe after it, stress work
    /// @p work, external work @p external, the points' kinetic energy after
    /// P2G minus the grid's after the update, and so on (@p transfer: the
    /// grid side of the transfer loss), re-map work @p remap, withheld
    /// work @p withheld; for the half-step term (SolidEnergies::half_step)
    /// the step @p dt and the node sums @p x = sum m v_old . dv and
    /// @p y = sum m dv . dv (dv = v_new - v_old, the step's velocity
    /// change; m dv / dt is the node's force, so x / dt = P_{k-1} and
    /// y / (2 dt) = dt/2 (P~_k - P_{k-1}), P~_k with the step's own force).
    void
    book_step(const double k_points,
              const double k_fe,
              const double work,
              const double external,
              const double transfer,
              const double remap,
              const double withheld,
              const double dt,
              const double x,
              const double y)
    {
      const double P = x / dt;
      if (H_dt > 0)
        H_sum += 0.5 * H_dt * (P - H_P);
      H_P  = P;
      H_dt = dt;
      H    = H_sum + 0.5 * y;
      K    = k_points + k_fe;
      W_int += work;
      W_ext += external;
      D_transfer += transfer - k_points; // k_points: point kinetic energy now
      W_remap += remap;
      W_withheld += withheld;
      K_p = k_points;
    }
    /// After a re-sort within a step whose points had @p k_step: the
    /// points' kinetic energy counted again, @p k_now, of which @p k_aside
    /// left the solid into detached drops (booked as melted); @p k_fe as
    /// in book_step().
    void
    book_resort(const double k_step,
                const double k_now,
                const double k_aside,
                const double k_fe)
    {
      D_transfer -= k_now + k_aside - k_step;
      K_melted += k_aside;
      K   = k_now + k_fe;
      K_p = k_now;
    }
    /// At a gather: the kinetic energy that melted points took out,
    /// @p k_melted, and solidified ones brought, @p k_solidified; the
    /// points' kinetic energy is now @p k_points.
    void
    book_exchange(const double k_melted,
                  const double k_solidified,
                  const double k_points)
    {
      K_melted += k_melted;
      K_solidified += k_solidified;
      K += k_points - K_p;
      K_p = k_points;
    }
    /// Kinetic energy @p e (global) taken out of the FE nodes between two
    /// steps (their velocities reduced), booked with the transfer
    /// dissipation.
    void
    take_fe_kinetic(const double e)
    {
      K -= e;
      D_transfer += e;
    }
    /// The masses changed by the factor @p r at kept velocities.
    void
    scale_kinetic(const double r)
    {
      K *= r;
      K_p *= r;
    }
    /// Kinetic energy of the solid now.
    double
    kinetic() const
    {
      return K;
    }
    /// Whether the kinetic energy and the stress work are finite.
    bool
    finite() const
    {
      return std::isfinite(K) && std::isfinite(W_int);
    }
    /// The energies, with the hourglass energies @p hourglass and
    /// @p hourglass_mode and the mass-scaling jump @p scaling_jump.
    SolidEnergies
    energies(const double hourglass,
             const double hourglass_mode,
             const double scaling_jump) const
    {
      SolidEnergies e;
      e.external        = W_ext;
      e.internal        = W_int;
      e.kinetic         = K;
      e.initial_kinetic = K0;
      e.hourglass       = hourglass;
      e.hourglass_mode  = hourglass_mode;
      e.transfer        = D_transfer;
      e.remap           = W_remap;
      e.withheld        = W_withheld;
      e.melted          = K_melted;
      e.solidified      = K_solidified;
      e.scaling_jump    = scaling_jump;
      e.half_step       = H;
      return e;
    }
    /// Checkpoint: the accounts in a fixed order (W_ext, W_int, K_0, K,
    /// D_transfer, K_melted, K_solidified, W_remap, K_points), and the
    /// withheld work (written last in the checkpoint).
    std::array<double, 9>
    saved_values() const
    {
      return {{W_ext,
               W_int,
               K0,
               K,
               D_transfer,
               K_melted,
               K_solidified,
               W_remap,
               K_p}};
    }
    /// From the 9 values of saved_values() at @p a.
    void
    restore(const double *a)
    {
      W_ext = a[0], W_int = a[1], K0 = a[2], K = a[3], D_transfer = a[4];
      K_melted = a[5], K_solidified = a[6], W_remap = a[7];
      K_p = a[8];
    }
    double
    withheld() const
    {
      return W_withheld;
    }
    void
    restore_withheld(const double w)
    {
      W_withheld = w;
    }
    /// Checkpoint: the half-step term's state (H, H_sum, H_P, H_dt), so
    /// that a resumed run's energy check reads the balance of the run that
    /// went on.
    std::array<double, 4>
    half_step_values() const
    {
      return {{H, H_sum, H_P, H_dt}};
    }
    /// From the 4 values of half_step_values().
    void
    restore_half_step(const std::array<double, 4> &a)
    {
      H = a[0], H_sum = a[1], H_P = a[2], H_dt = a[3];
    }

  private:
    double W_ext = 0, W_int = 0, K0 = 0, K = 0;
    double D_transfer = 0, K_melted = 0, K_solidified = 0;
    /// re-map work of the MUSL update, with the velocity jumps of the FE
    /// node forces at the transition nodes
    double W_remap = 0;
    /// SolidEnergies::withheld, summed over the steps, J.
    double W_withheld = 0;
    double K_p        = 0; ///< kinetic energy of the points
    /// SolidEnergies::half_step after the last step, J; H_sum: its part
    /// up to the step before, H_P and H_dt: P_{k-1} and dt_k of the last
    /// step (book_step()).
    double H = 0, H_sum = 0, H_P = 0, H_dt = 0;
  };
} // namespace femp

#endif
