// femp: the watchdog thread that prints a line when a run has said nothing
// for 30 s of wall time (see the header). No paper equations.
#include <femp/base/progress_watchdog.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

namespace femp
{
  namespace progress
  {
    namespace
    {
      using Clock = std::chrono::steady_clock;

      struct Watchdog
      {
        std::atomic<const char *> phase{"setting up"};
        std::atomic<double>       time{0.};
        std::atomic<unsigned int> step{0};
        std::atomic<unsigned int> n_sub{0};
        std::atomic<double>       dt_sub{0.};
        std::atomic<long long>    last_line{0}; // ns since start
        Clock::time_point         t0       = Clock::now();
        double                    interval = 30.;
        std::thread               thread;
        std::mutex                mutex;
        std::condition_variable   wake;
        bool                      stopping = false;

        long long
        now() const
        {
          return std::chrono::duration_cast<std::chrono::nanoseconds>(
                   Clock::now() - t0)
            .count();
        }

        void
        loop()
        {
          std::unique_lock<std::mutex> lock(mutex);
          while (!stopping)
            {
              wake.wait_for(lock, std::chrono::milliseconds(250));
              if (stopping)
                break;
              const long long t = now();
              if (t - last_line.load() < interval * 1e9)
                continue;
              last_line = t;
              std::ostringstream s;
              s << "femp: still working: " << phase.load() << " (simulated "
                << "time " << std::setprecision(6) << time.load() << " s, step "
                << step.load();
              if (n_sub.load() > 0)
                s << ", sub-step " << n_sub.load() << " (each " << dt_sub.load()
                  << " s)";
              s << ", wall " << std::setprecision(4) << t * 1e-9 << " s)\n";
              std::cout << s.str() << std::flush;
            }
        }

        ~Watchdog()
        {
          stop_thread();
        }

        void
        stop_thread()
        {
          {
            std::lock_guard<std::mutex> lock(mutex);
            stopping = true;
          }
          wake.notify_all();
          if (thread.joinable())
            thread.join();
        }
      };

      Watchdog dog;
    } // namespace

    void
    start(const MPI_Comm comm, const double interval)
    {
      if (dealii::Utilities::MPI::this_mpi_process(comm) != 0 ||
          dog.thread.joinable())
        return;
      dog.interval  = interval;
      dog.stopping  = false;
      dog.last_line = dog.now();
      dog.thread    = std::thread([] { dog.loop(); });
    }

    void
    stop()
    {
      dog.stop_thread();
    }

    void
    phase(const char *name)
    {
      dog.phase = name;
      dog.n_sub = 0;
    }

    void
    time(const double t, const unsigned int step)
    {
      dog.time = t;
      dog.step = step;
    }

    void
    substep(const unsigned int n, const double dt)
    {
      dog.n_sub  = n;
      dog.dt_sub = dt;
    }

    void
    reported()
    {
      dog.last_line = dog.now();
    }
  } // namespace progress
} // namespace femp
