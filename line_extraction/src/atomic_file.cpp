#include "linemap/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace linemap
{
void writeFileAtomically(const std::string& path, const std::string& bytes, const std::string& kind)
{
  const std::string where = kind + " '" + path + "': ";
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error(where + "cannot create '" + tmp + "': " + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size())
  {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0)
    {
      if (errno == EINTR) continue;
      const std::string err = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error(where + "write failed: " + err);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0)
  {
    const std::string err = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error(where + "fsync/close failed: " + err);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0)
  {
    const std::string err = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error(where + "rename failed: " + err);
  }
}

std::string readWholeFile(const std::string& path, const std::string& kind)
{
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(kind + " '" + path + "': cannot open: " + std::strerror(errno));
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace linemap
