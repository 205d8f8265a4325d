// femp: one run per output folder: the lock file of the output directory
// (see the header). No paper equations.
#include <femp/io/output_lock.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <unistd.h>
#include <vector>

namespace femp
{
  namespace
  {
    /// Lock files this process holds; removed at exit.
    struct HeldLocks
    {
      std::vector<std::string> files;
      ~HeldLocks()
      {
        for (const auto &f : files)
          {
            std::error_code ec;
            std::filesystem::remove(f, ec);
          }
      }
    };
    HeldLocks held;

    std::string
    this_host()
    {
      char name[256] = {};
      if (gethostname(name, sizeof(name) - 1) != 0)
        return "unknown";
      return name;
    }

    std::string
    now_utc()
    {
      const std::time_t t = std::time(nullptr);
      std::tm           tm{};
      gmtime_r(&t, &tm);
      char text[32];
      std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M:%S UTC", &tm);
      return text;
    }

    /// What a lock file says about its holder.
    struct Holder
    {
      bool        valid = false;
      long        pid   = 0;
      std::string host, start;
    };

    Holder
    read_holder(const std::string &file)
    {
      Holder        h;
      std::ifstream in(file);
      std::string   key, line;
      while (std::getline(in, line))
        {
          const auto space = line.find(' ');
          if (space == std::string::npos)
            continue;
          key                     = line.substr(0, space);
          const std::string value = line.substr(space + 1);
          if (key == "pid")
            h.pid = std::atol(value.c_str());
          else if (key == "host")
            h.host = value;
          else if (key == "start")
            h.start = value;
        }
      h.valid = h.pid > 0 && !h.host.empty();
      return h;
    }

    /// Create @p file exclusively with this process's identity.
    bool
    create_exclusive(const std::string &file, std::string &error)
    {
      const int fd = ::open(file.c_str(), O_CREAT | O_EXCL | O_WRONLY, 0644);
      if (fd < 0)
        {
          if (errno != EEXIST)
            error = "cannot create the lock file '" + file +
                    "': " + std::strerror(errno);
          return false;
        }
      std::ostringstream s;
      s << "pid " << ::getpid() << "\nhost " << this_host() << "\nstart "
        << now_utc() << "\n";
      const std::string text = s.str();
      const bool        ok =
        ::write(fd, text.data(), text.size()) == ssize_t(text.size());
      ::close(fd);
      if (!ok)
        error = "cannot write the lock file '" + file + "'";
      return ok;
    }

    /// Rank 0: take the lock; the refusal's message, or "".
    std::string
    take(const std::string &directory, std::string &note)
    {
      const std::string file  = directory + "/" + OutputLock::file_name;
      const std::string host  = this_host();
      std::string       error = "";
      for (unsigned int attempt = 0; attempt < 20; ++attempt)
        {
          if (create_exclusive(file, error))
            {
              held.files.push_back(file);
              return "";
            }
          if (!error.empty())
            return error;
          const Holder h = read_holder(file);
          if (!h.valid)
            {
              // Just created by another run that has not written it yet:
              // look again (2 s in all), then refuse.
              std::this_thread::sleep_for(std::chrono::milliseconds(100));
              continue;
            }
          if (h.pid == ::getpid() && h.host == host)
            return ""; // this process (a second problem in one program)
          const bool gone =
            h.host == host && ::kill(pid_t(h.pid), 0) != 0 && errno == ESRCH;
          if (!gone)
            return "another run of femp writes into this folder (pid " +
                   std::to_string(h.pid) + " on host " + h.host + ", started " +
                   h.start + ", lock file '" + file +
                   "'): choose another 'Output/Directory', wait for that "
                   "run to end, or remove the lock file if no run uses the "
                   "folder" +
                   (h.host != host ? " (it is held from another host, whose "
                                     "processes femp cannot see)" :
                                     std::string());
          note = "femp: note: taking over the lock of '" + directory +
                 "' left by an earlier run that is gone (pid " +
                 std::to_string(h.pid) + " on host " + h.host + ", started " +
                 h.start + "; killed or aborted?)";
          std::error_code ec;
          std::filesystem::remove(file, ec);
        }
      return "the lock file '" + file +
             "' exists but names no run (pid and host); remove it if no run "
             "uses the folder";
    }
  } // namespace

  std::string
  OutputLock::acquire(const std::string &directory,
                      const MPI_Comm     comm,
                      std::string       &note)
  {
    std::string error;
    if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
      error = take(directory, note);
    return dealii::Utilities::MPI::broadcast(comm, error, 0);
  }

  void
  OutputLock::release_all()
  {
    for (const auto &f : held.files)
      {
        std::error_code ec;
        std::filesystem::remove(f, ec);
      }
    held.files.clear();
  }
} // namespace femp
