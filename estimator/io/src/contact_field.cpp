#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <unistd.h>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/fnv1a.hpp"
#include "inhand/io/mesh_io.hpp"
#include "inhand/io/object_loader.hpp"

namespace fs = std::filesystem;

namespace inhand {

namespace {

constexpr char kMagic[8] = {'i', 'n', 'h', 'S', 'D', 'F', '0', '1'};

bool ReadField(const fs::path& path, DistanceField& f) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  char magic[8];
  std::int32_t dims[3];
  double origin[3], spacing;
  std::uint32_t source_len;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(dims), sizeof dims);
  in.read(reinterpret_cast<char*>(origin), sizeof origin);
  in.read(reinterpret_cast<char*>(&spacing), sizeof spacing);
  in.read(reinterpret_cast<char*>(&source_len), sizeof source_len);
  if (!in || std::memcmp(magic, kMagic, 8) != 0 || source_len > 4096) return false;
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 2 || dims[a] > 100000) return false;
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  if (n > 400'000'000ULL || !(spacing > 0.0)) return false;
  f.source.resize(source_len);
  in.read(f.source.data(), source_len);
  f.values.resize(n);
  in.read(reinterpret_cast<char*>(f.values.data()),
          static_cast<std::streamsize>(n * sizeof(float)));
  if (!in || in.peek() != std::ifstream::traits_type::eof()) return false;
  f.dims = Eigen::Vector3i(dims[0], dims[1], dims[2]);
  f.origin = Vec3(origin[0], origin[1], origin[2]);
  f.spacing = spacing;
  return true;
}

void WriteField(const fs::path& path, const DistanceField& f) {
  const fs::path tmp = path.string() + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) return;
    const std::int32_t dims[3] = {f.dims[0], f.dims[1], f.dims[2]};
    const double origin[3] = {f.origin.x(), f.origin.y(), f.origin.z()};
    const auto source_len = static_cast<std::uint32_t>(f.source.size());
    out.write(kMagic, 8);
    out.write(reinterpret_cast<const char*>(dims), sizeof dims);
    out.write(reinterpret_cast<const char*>(origin), sizeof origin);
    out.write(reinterpret_cast<const char*>(&f.spacing), sizeof f.spacing);
    out.write(reinterpret_cast<const char*>(&source_len), sizeof source_len);
    out.write(f.source.data(), source_len);
    out.write(reinterpret_cast<const char*>(f.values.data()),
              static_cast<std::streamsize>(f.values.size() * sizeof(float)));
    if (!out) {
      out.close();
      std::error_code ec;
      fs::remove(tmp, ec);
      return;
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);  // atomic: concurrent loaders see the old state or the whole file
  if (ec) fs::remove(tmp, ec);
}

}  // namespace

void ContactFieldOptions::Validate(const std::string& where) const {
  if (source != "auto" && source != "visual" && source != "pieces" && source != "none")
    throw InputError(where + ": contact field 'source' is '" + source +
                     "', expected \"auto\", \"visual\", \"pieces\" or \"none\"");
  params.Validate(where);
}

std::string ResolveContactFieldSource(const ObjectModel& obj, const ContactFieldOptions& options,
                                      const std::string& where) {
  std::vector<const TriangleMesh*> visual;
  for (const TriangleMesh& m : obj.visual) visual.push_back(&m);
  if (options.source == "visual") {
    if (!IsWatertightForParity(visual))
      throw InputError(where +
                       ": contact field source \"visual\" needs closed visual meshes (an edge "
                       "is used unevenly: the mesh has a hole)");
    return "visual";
  }
  if (options.source != "auto") return options.source;
  if (obj.pieces.size() <= 1) return "none";  // one convex piece: GJK is exact
  return IsWatertightForParity(visual) ? "visual" : "pieces";
}

void AttachContactField(ObjectModel& obj, const ContactFieldOptions& options,
                        const std::string& where) {
  options.Validate(where);
  const std::string source = ResolveContactFieldSource(obj, options, where);
  obj.field.reset();
  obj.field_cache.clear();
  if (source == "none") return;
  detail::Fnv1a h;  // the cache key: the geometry the field is built from and the parameters
  h.Mix("inhand-sdf-1", 12);
  h.Mix(source.data(), source.size());
  h.Mix(options.params.spacing);
  h.Mix(options.params.padding);
  h.Mix(&options.params.max_nodes, sizeof options.params.max_nodes);
  if (source == "visual") {
    for (const TriangleMesh& m : obj.visual) {
      for (const Vec3& v : m.vertices) h.Mix(v);
      for (const auto& t : m.triangles) h.Mix(t.data(), 3 * sizeof(int));
    }
  } else {
    for (const ConvexPiece& p : obj.pieces) {
      const int kind = static_cast<int>(p.kind);
      h.Mix(&kind, sizeof kind);
      h.Mix(p.T_BS.matrix().data(), 16 * sizeof(double));
      h.Mix(p.half_extents);
      h.Mix(p.radius);
      h.Mix(p.half_length);
      for (const Vec3& v : p.hull_vertices) h.Mix(v);
    }
  }
  const fs::path dir = CacheDirectory(options.cache_dir);
  std::ostringstream name;
  name << "sdf-" << std::hex << std::setw(16) << std::setfill('0') << h.value() << ".bin";
  const fs::path cached = dir / name.str();
  auto field = std::make_shared<DistanceField>();
  if (!ReadField(cached, *field)) {
    if (source == "visual") {
      std::vector<const TriangleMesh*> visual;
      for (const TriangleMesh& m : obj.visual) visual.push_back(&m);
      *field = BuildDistanceFieldFromMesh(visual, options.params);
    } else {
      *field = BuildDistanceFieldFromPieces(obj.pieces, options.params);
    }
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!ec) WriteField(cached, *field);  // an unwritable cache only costs time
  }
  obj.field = std::move(field);
  obj.field_cache = cached.string();
}

}  // namespace inhand
