#include "beslam/formats/ply.hpp"

#include <cstdint>
#include <cstring>
#include <ostream>
#include <sstream>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"

namespace beslam::formats {

void writePlyMesh(const std::string& path, const TriangleMesh& mesh, const Eigen::Isometry3d& T,
                  const std::string& comment) {
  writeFileAtomic(path, [&](std::ostream& out) {
    out << "ply\nformat binary_little_endian 1.0\ncomment " << comment << "\nelement vertex " << mesh.vertices.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << mesh.faces.size()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& v : mesh.vertices) {
      const Eigen::Vector3f w = (T * v).cast<float>();
      out.write(reinterpret_cast<const char*>(w.data()), 3 * sizeof(float));  // x86/ARM: little endian
    }
    for (const auto& f : mesh.faces) {
      const unsigned char three = 3;
      const std::int32_t idx[3] = {f[0], f[1], f[2]};
      out.write(reinterpret_cast<const char*>(&three), 1);
      out.write(reinterpret_cast<const char*>(idx), sizeof(idx));
    }
  });
}

TriangleMesh readPlyMesh(const std::string& path) {
  const std::string data = readFile(path);
  const size_t end = data.find("end_header\n");
  if (data.compare(0, 4, "ply\n") != 0 || end == std::string::npos) throwAt(path, "not a PLY file");
  std::istringstream header(data.substr(0, end));
  std::string line, format, element;
  long nv = -1, nf = -1, vertex_properties = 0;
  while (std::getline(header, line)) {
    std::istringstream ls(line);
    std::string key, a, b;
    ls >> key >> a >> b;
    try {
      if (key == "format") format = a;
      if (key == "element") element = a;
      if (key == "element" && a == "vertex") nv = std::stol(b);
      if (key == "element" && a == "face") nf = std::stol(b);
    } catch (const std::exception&) {
      throwAt(path, "PLY header line '" + line + "' has no count");
    }
    if (key == "property" && element == "vertex") ++vertex_properties;
  }
  if (nv < 0 || nf < 0) throwAt(path, "PLY header without vertex or face counts");
  if (vertex_properties < 3) throwAt(path, "PLY vertices without x y z");
  TriangleMesh mesh;
  const char* p = data.data() + end + 11;
  const char* stop = data.data() + data.size();
  if (format == "binary_little_endian") {
    if (vertex_properties != 3) throwAt(path, "binary PLY vertices must be float x y z only");
    const auto avail = static_cast<unsigned long>(stop - p);  // counts checked before they multiply
    if (static_cast<unsigned long>(nv) > avail / 12 || static_cast<unsigned long>(nf) > avail / 13 ||
        static_cast<unsigned long>(nv) * 12 + static_cast<unsigned long>(nf) * 13 > avail)
      throwAt(path, "PLY file truncated");
    for (long i = 0; i < nv; ++i, p += 12) {
      float v[3];
      std::memcpy(v, p, 12);
      mesh.vertices.emplace_back(v[0], v[1], v[2]);
    }
    for (long i = 0; i < nf; ++i, p += 13) {
      if (static_cast<unsigned char>(*p) != 3) throwAt(path, "PLY face " + std::to_string(i) + " is not a triangle");
      std::int32_t idx[3];
      std::memcpy(idx, p + 1, 12);
      mesh.faces.push_back({idx[0], idx[1], idx[2]});
    }
  } else if (format == "ascii") {
    std::istringstream body(std::string(p, stop));
    for (long i = 0; i < nv; ++i) {
      if (!std::getline(body, line)) throwAt(path, "PLY file truncated");
      std::istringstream ls(line);
      Eigen::Vector3d v;
      if (!(ls >> v.x() >> v.y() >> v.z())) throwAt(path, "PLY vertex " + std::to_string(i) + " unreadable");
      mesh.vertices.push_back(v);
    }
    for (long i = 0; i < nf; ++i) {
      int k, a, b, c;
      if (!(body >> k >> a >> b >> c) || k != 3) throwAt(path, "PLY face " + std::to_string(i) + " unreadable");
      mesh.faces.push_back({a, b, c});
    }
  } else {
    throwAt(path, "PLY format '" + format + "' not supported");
  }
  for (const auto& f : mesh.faces)
    for (int i : f)
      if (i < 0 || i >= static_cast<int>(mesh.vertices.size())) throwAt(path, "PLY face index out of range");
  return mesh;
}

}  // namespace beslam::formats
