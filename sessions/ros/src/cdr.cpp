#include "cdr.hpp"

#include <cstring>

#include "inhand/core/error.hpp"

namespace inhand::ros {

namespace {

// One reader for both serialisations: CDR (an encapsulation header, primitives aligned to their
// size, strings with a terminating NUL, Time as int32 sec + uint32 nanosec) and ROS 1's (no
// header, no alignment, little endian, strings without NUL, Header with a seq first, Time as
// uint32 sec + uint32 nsec). Every length is checked against the bytes left before anything is
// allocated.
class CdrReader {
 public:
  CdrReader(const std::uint8_t* data, std::size_t size, const std::string& context, bool ros1)
      : ros1_(ros1), context_(context) {
    if (ros1) {
      p_ = data;
      n_ = size;
      return;
    }
    if (size < 4) Fail("shorter than the 4-byte CDR encapsulation header");
    // Encapsulation kinds: 0x0000 CDR big endian, 0x0001 CDR little endian (ROS 2's XCDR1).
    if (data[0] != 0 || data[1] > 1)
      Fail("unsupported CDR encapsulation " + std::to_string(data[0]) + "," +
           std::to_string(data[1]) + " (expected CDR_LE or CDR_BE)");
    little_ = data[1] == 1;
    p_ = data + 4;
    n_ = size - 4;
  }

  template <class T>
  T Prim() {
    Align(sizeof(T));
    Need(sizeof(T));
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, p_ + pos_, sizeof(T));
    if (!little_)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    T v;
    std::memcpy(&v, b, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  double F64() { return Prim<double>(); }
  std::uint32_t U32() { return Prim<std::uint32_t>(); }

  std::string String() {
    const std::uint32_t len = U32();  // CDR: including the terminating NUL
    Need(len);
    std::string s;
    if (len > 0)
      s.assign(reinterpret_cast<const char*>(p_ + pos_),
               len - (!ros1_ && p_[pos_ + len - 1] == 0 ? 1 : 0));
    pos_ += len;
    return s;
  }
  std::uint32_t Count(std::size_t min_element_size) {
    const std::uint32_t c = U32();
    if (static_cast<std::uint64_t>(c) * min_element_size > n_ - pos_)
      Fail("sequence of " + std::to_string(c) + " elements runs past the end");
    return c;
  }
  std::vector<double> DoubleSeq() {
    const std::uint32_t c = Count(8);
    std::vector<double> v(c);
    for (auto& x : v) x = F64();
    return v;
  }
  void Bytes(std::vector<std::uint8_t>* out, bool keep) {
    const std::uint32_t c = Count(1);
    if (keep) out->assign(p_ + pos_, p_ + pos_ + c);
    pos_ += c;
  }
  Header ReadHeader() {
    Header h;
    if (ros1_) U32();  // seq
    const std::int64_t sec = ros1_ ? std::int64_t{U32()} : std::int64_t{Prim<std::int32_t>()};
    const std::uint32_t nsec = U32();
    if (nsec >= 1000000000u)
      Fail("header stamp has " + std::to_string(nsec) + " nanoseconds (expected < 1e9)");
    h.stamp_ns = sec * 1000000000LL + nsec;
    h.frame_id = String();
    return h;
  }
  Vec3 Vector3() {
    const double x = F64(), y = F64(), z = F64();
    return Vec3(x, y, z);
  }
  Quat Quaternion() {
    const double x = F64(), y = F64(), z = F64(), w = F64();
    return MessageQuaternion(w, x, y, z, context_);
  }
  ros::Pose ReadPose() {
    const Vec3 t = Vector3();
    return {t, Quaternion()};
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(context_ + ": " + what);
  }

 private:
  void Align(std::size_t a) {
    if (!ros1_) pos_ = (pos_ + a - 1) / a * a;
  }
  void Need(std::size_t k) const {
    if (pos_ > n_ || k > n_ - pos_)
      Fail(std::string("truncated ") + (ros1_ ? "message" : "CDR data") + " (" +
           std::to_string(n_) + " bytes)");
  }
  const std::uint8_t* p_ = nullptr;
  std::size_t n_ = 0, pos_ = 0;
  bool little_ = true;
  bool ros1_ = false;
  const std::string& context_;
};

}  // namespace

Payload Decode(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images,
               const std::string& context, bool ros1) {
  CdrReader r(data, size, context, ros1);
  switch (type) {
    case MsgType::kJointState: {
      JointStateMsg m;
      m.header = r.ReadHeader();
      const std::uint32_t n = r.Count(4);
      m.name.resize(n);
      for (auto& s : m.name) s = r.String();
      m.position = r.DoubleSeq();
      m.velocity = r.DoubleSeq();
      m.effort = r.DoubleSeq();
      return m;
    }
    case MsgType::kImage: {
      ImageMsg m;
      m.header = r.ReadHeader();
      m.height = r.U32();
      m.width = r.U32();
      m.encoding = r.String();
      m.is_bigendian = r.Prim<std::uint8_t>();
      m.step = r.U32();
      r.Bytes(&m.data, decode_images);
      return m;
    }
    case MsgType::kCompressedImage: {
      CompressedImageMsg m;
      m.header = r.ReadHeader();
      m.format = r.String();
      r.Bytes(&m.data, decode_images);
      return m;
    }
    case MsgType::kCameraInfo: {
      CameraInfoMsg m;
      m.header = r.ReadHeader();
      m.height = r.U32();
      m.width = r.U32();
      m.distortion_model = r.String();
      m.d = r.DoubleSeq();
      for (auto& v : m.k) v = r.F64();
      for (auto& v : m.r) v = r.F64();
      for (auto& v : m.p) v = r.F64();
      return m;  // binning and ROI are not used
    }
    case MsgType::kTf: {
      TfMsg m;
      const std::uint32_t n = r.Count(8);
      m.transforms.resize(n);
      for (auto& t : m.transforms) {
        t.header = r.ReadHeader();
        t.child_frame_id = r.String();
        t.T = r.ReadPose();
      }
      return m;
    }
    case MsgType::kTransformStamped: {
      StampedTransform t;
      t.header = r.ReadHeader();
      t.child_frame_id = r.String();
      t.T = r.ReadPose();
      return t;
    }
    case MsgType::kPoseStamped: {
      StampedTransform t;
      t.header = r.ReadHeader();
      t.T = r.ReadPose();
      return t;
    }
    case MsgType::kOdometry: {
      StampedTransform t;
      t.header = r.ReadHeader();
      t.child_frame_id = r.String();
      t.T = r.ReadPose();
      return t;  // covariance and twist are not used
    }
    case MsgType::kOther:
      break;
  }
  return std::monostate();
}

Payload DecodeCdr(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images,
                  const std::string& context) {
  return Decode(type, data, size, decode_images, context, false);
}

Payload DecodeRos1(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images,
                   const std::string& context) {
  return Decode(type, data, size, decode_images, context, true);
}

}  // namespace inhand::ros
