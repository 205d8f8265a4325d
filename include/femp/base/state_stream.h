// femp: StateWriter and StateReader, the byte streams in which every module
// saves and restores its state for a checkpoint (the file layout is
// Checkpoint's, io/checkpoint.h; doc/checkpoint.md). No equation of the
// paper.
#ifndef femp_state_stream_h
#define femp_state_stream_h

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace femp
{
  /// Bytes of one module's state on one rank (plain copies of trivially
  /// copyable values; vectors and strings with their length first).
  class StateWriter
  {
  public:
    template <typename T>
    void
    put(const T &value)
    {
      static_assert(std::is_trivially_copyable<T>::value,
                    "only plain values are written");
      const char *p = reinterpret_cast<const char *>(&value);
      data.insert(data.end(), p, p + sizeof(T));
    }
    template <typename T>
    void
    put_vector(const std::vector<T> &values)
    {
      static_assert(std::is_trivially_copyable<T>::value,
                    "only plain values are written");
      put<std::uint64_t>(values.size());
      const char *p = reinterpret_cast<const char *>(values.data());
      data.insert(data.end(), p, p + sizeof(T) * values.size());
    }
    void
    put_string(const std::string &s)
    {
      put<std::uint64_t>(s.size());
      data.insert(data.end(), s.begin(), s.end());
    }
    const std::vector<char> &
    bytes() const
    {
      return data;
    }

  private:
    std::vector<char> data;
  };

  /// Reads what a StateWriter wrote; throws (naming @p what) on reading past
  /// the end, which a checksum-verified file only does when the format of
  /// the writer and the reader differ.
  class StateReader
  {
  public:
    StateReader(const char        *begin,
                const std::size_t  size,
                const std::string &what)
        : p(begin)
        , end(begin + size)
        , what(what)
    {
    }
    template <typename T>
    T
    get()
    {
      static_assert(std::is_trivially_copyable<T>::value,
                    "only plain values are read");
      T value;
      check(sizeof(T));
      std::memcpy(&value, p, sizeof(T));
      p += sizeof(T);
      return value;
    }
    template <typename T>
    std::vector<T>
    get_vector()
    {
      const auto n = get<std::uint64_t>();
      check(n * sizeof(T));
      std::vector<T> values(n);
      std::memcpy(values.data(), p, n * sizeof(T));
      p += n * sizeof(T);
      return values;
    }
    std::string
    get_string()
    {
      const auto n = get<std::uint64_t>();
      check(n);
      std::string s(p, p + n);
      p += n;
      return s;
    }
    /// Skip @p n bytes.
    void
    skip(const std::uint64_t n)
    {
      check(n);
      p += n;
    }
    bool
    at_end() const
    {
      return p == end;
    }

  private:
    const char *p, *end;
    std::string what;
    void
    check(const std::uint64_t n) const;
  };
} // namespace femp

#endif
