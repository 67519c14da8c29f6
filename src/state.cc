#include "lsgd/state.h"

#include <cstring>
#include <set>

#include "internal/check.h"

namespace lsgd {
namespace {

template <typename T>
void put_le(std::vector<std::uint8_t>& out, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    out.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i)));
  }
}

template <typename T>
T get_le(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return static_cast<T>(v);
}

}  // namespace

void StateWriter::put_i64(std::int64_t v) { put_le(bytes_, static_cast<std::uint64_t>(v)); }

void StateWriter::put_f64(double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  put_le(bytes_, bits);
}

void StateWriter::put_f32s(const float* v, std::size_t n) {
  bytes_.reserve(bytes_.size() + 4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &v[i], sizeof bits);
    put_le(bytes_, bits);
  }
}

void StateWriter::put_bytes(const std::uint8_t* data, std::size_t n) {
  bytes_.insert(bytes_.end(), data, data + n);
}

void check_state_version(const std::string& what, const char* component, std::uint32_t version,
                         std::uint32_t newest) {
  if (version < 1 || version > newest) {
    internal::throw_invalid(what, ": version ", version, " of ", component,
                            "'s state is not one this lsgd reads (1 to ", newest, ")");
  }
}

void StateReader::need(std::size_t n) const {
  if (!present_ && n > 0) internal::throw_invalid(what_, ": there is no record");
  if (n > size_ - pos_) {
    internal::throw_invalid(what_, ": the record has ", size_, " bytes, too few for its content");
  }
}

std::int64_t StateReader::get_i64() {
  need(8);
  const auto v = static_cast<std::int64_t>(get_le<std::uint64_t>(data_ + pos_));
  pos_ += 8;
  return v;
}

double StateReader::get_f64() {
  need(8);
  const std::uint64_t bits = get_le<std::uint64_t>(data_ + pos_);
  pos_ += 8;
  double v = 0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

void StateReader::get_f32s(float* out, std::size_t n) {
  if (n > (size_ - pos_) / 4) {
    internal::throw_invalid(what_, ": the record has ", size_, " bytes, too few for its content");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t bits = get_le<std::uint32_t>(data_ + pos_ + 4 * i);
    std::memcpy(&out[i], &bits, sizeof bits);
  }
  pos_ += 4 * n;
}

const std::uint8_t* StateReader::get_bytes(std::size_t n) {
  need(n);
  const std::uint8_t* p = data_ + pos_;
  pos_ += n;
  return p;
}

void StateReader::finish() const {
  if (pos_ != size_) {
    internal::throw_invalid(what_, ": the record has ", size_ - pos_, " bytes more than its content");
  }
}

std::vector<std::uint8_t> encode_records(const std::vector<StateRecord>& records) {
  std::vector<std::uint8_t> out;
  put_le(out, static_cast<std::uint32_t>(records.size()));
  for (const StateRecord& r : records) {
    if (r.component.empty() || r.component.size() > 0xFFFF || r.bytes.size() > 0xFFFFFFFFu) {
      internal::throw_invalid("state record of '", r.component, "': name or size out of range");
    }
    put_le(out, static_cast<std::uint16_t>(r.component.size()));
    out.insert(out.end(), r.component.begin(), r.component.end());
    put_le(out, r.version);
    put_le(out, static_cast<std::uint32_t>(r.bytes.size()));
    out.insert(out.end(), r.bytes.begin(), r.bytes.end());
  }
  return out;
}

std::vector<StateRecord> decode_records(const std::uint8_t* data, std::size_t size) {
  std::size_t pos = 0;
  const auto need = [&](std::size_t n, const char* what) {
    if (n > size - pos) {
      internal::throw_invalid("frame state of ", size, " bytes is cut in ", what, " at byte ", pos);
    }
  };
  need(4, "its record count");
  const auto count = get_le<std::uint32_t>(data);
  pos = 4;
  std::vector<StateRecord> records;
  std::set<std::string> names;
  for (std::uint32_t i = 0; i < count; ++i) {
    need(2, "a record name's length");
    const auto length = get_le<std::uint16_t>(data + pos);
    pos += 2;
    need(length, "a record name");
    StateRecord r;
    r.component.assign(reinterpret_cast<const char*>(data + pos), length);
    pos += length;
    need(8, "a record header");
    r.version = get_le<std::uint32_t>(data + pos);
    const auto n = get_le<std::uint32_t>(data + pos + 4);
    pos += 8;
    need(n, "a record");
    r.bytes.assign(data + pos, data + pos + n);
    pos += n;
    if (r.component.empty() || !names.insert(r.component).second) {
      internal::throw_invalid("frame state has ", r.component.empty() ? "a record without a name"
                                                                       : "two records of '" +
                                                                             r.component + "'");
    }
    records.push_back(std::move(r));
  }
  if (pos != size) {
    internal::throw_invalid("frame state has ", size - pos, " bytes after its ", count, " records");
  }
  return records;
}

}  // namespace lsgd
