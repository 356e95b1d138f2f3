#include "io/ply.hpp"

#include <bit>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/output_file.hpp"

namespace eds {

static_assert(std::endian::native == std::endian::little, "PLY writer assumes a little-endian host");

void writePly(const std::filesystem::path& file, const PointCloud& cloud) {
  if (cloud.intensity.size() != cloud.xyz.size())
    throw std::invalid_argument("writePly: intensity and xyz differ in length");
  OutputFile target(file);
  std::ofstream out(target.temporary(), std::ios::binary);
  if (!out) throw InputError(file.string(), "cannot open for writing");
  out << "ply\nformat binary_little_endian 1.0\ncomment written by eds\n"
      << "element vertex " << cloud.xyz.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\nproperty float intensity\nend_header\n";
  for (std::size_t i = 0; i < cloud.xyz.size(); ++i) {
    float rec[4] = {cloud.xyz[i].x(), cloud.xyz[i].y(), cloud.xyz[i].z(), cloud.intensity[i]};
    out.write(reinterpret_cast<const char*>(rec), sizeof rec);
  }
  out.close();
  if (!out) throw InputError(file.string(), "write failed");
  target.commit();
}

PointCloud readPly(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "file not found");
  std::string line;
  std::size_t line_no = 0, count = 0;
  std::vector<std::string> props;
  bool binary_le = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1 && line != "ply") throw InputError(file.string(), 1, "not a PLY file");
    std::istringstream ss(line);
    std::string key;
    ss >> key;
    if (key == "format") {
      std::string fmt;
      ss >> fmt;
      binary_le = fmt == "binary_little_endian";
    } else if (key == "element") {
      std::string what;
      ss >> what >> count;
      if (what != "vertex") throw InputError(file.string(), line_no, "only vertex elements are supported");
    } else if (key == "property") {
      std::string type, name;
      ss >> type >> name;
      if (type != "float") throw InputError(file.string(), line_no, "only float properties are supported");
      props.push_back(name);
    } else if (key == "end_header") {
      break;
    }
  }
  if (!binary_le) throw InputError(file.string(), "only binary_little_endian PLY is supported");
  if (props.size() < 3 || props[0] != "x" || props[1] != "y" || props[2] != "z")
    throw InputError(file.string(), "expected float properties x y z first");
  const bool has_intensity = props.size() > 3 && props[3] == "intensity";
  // The header's count against what the file holds, before anything is allocated for it.
  const auto data_start = static_cast<std::uintmax_t>(in.tellg());
  const std::uintmax_t size = std::filesystem::file_size(file);
  const std::uintmax_t record = props.size() * sizeof(float);
  if (data_start > size || count > (size - data_start) / record)
    throw InputError(file.string(), "truncated: the header says " + std::to_string(count) +
                                        " vertices, the file holds " +
                                        std::to_string(data_start > size ? 0 : (size - data_start) / record));
  PointCloud cloud;
  cloud.xyz.resize(count);
  cloud.intensity.assign(count, 0.f);
  std::vector<float> rec(props.size());
  for (std::size_t i = 0; i < count; ++i) {
    if (!in.read(reinterpret_cast<char*>(rec.data()),
                 static_cast<std::streamsize>(rec.size() * sizeof(float))))
      throw InputError(file.string(),
                       "truncated: vertex " + std::to_string(i) + " of " + std::to_string(count));
    cloud.xyz[i] = {rec[0], rec[1], rec[2]};
    if (has_intensity) cloud.intensity[i] = rec[3];
  }
  return cloud;
}

}  // namespace eds
