#include "io/hdf5_events.hpp"

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "io/hdf5_common.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

using hdf5::failH5;
using hdf5::floorDiv;
using hdf5::Hid;
using hdf5::kBloscFilter;
using hdf5::loadBlosc;
using hdf5::QuietHdf5;

enum Field { kT = 0, kX = 1, kY = 2, kP = 3 };
constexpr std::array<const char*, 4> kFieldNames = {"t", "x", "y", "p"};

// Called by HDF5 when a stored value does not fit the memory type: the default would clip it
// silently (a negative x would become 0), so the read is aborted and reported instead.
H5T_conv_ret_t abortOnOverflow(H5T_conv_except_t type, hid_t, hid_t, void*, void*, void* flag) {
  if (type != H5T_CONV_EXCEPT_RANGE_HI && type != H5T_CONV_EXCEPT_RANGE_LOW) {
    return H5T_CONV_UNHANDLED;
  }
  *static_cast<bool*>(flag) = true;
  return H5T_CONV_ABORT;
}

// Finds the one dataset, checks that it is a non-empty 1-D integer array whose filters HDF5 can
// load, and opens it with a chunk cache that holds at least a few chunks: sequential hyperslab
// reads that end inside a chunk would otherwise decompress that chunk twice.
Hid openDataset(hid_t file, const std::string& path, const char* name, std::size_t* length) {
  const std::string full(name);
  const auto slash = full.find('/');
  if (slash != std::string::npos && H5Lexists(file, full.substr(0, slash).c_str(), H5P_DEFAULT) <= 0) {
    throw InputError(path, "missing group '" + full.substr(0, slash) + "' (expected " + full + ")");
  }
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0) throw InputError(path, "missing dataset " + full);
  Hid ds(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) failH5(path, full + " is not a dataset");
  Hid space(H5Dget_space(ds.get()), H5Sclose);
  Hid type(H5Dget_type(ds.get()), H5Tclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (H5Tget_class(type.get()) != H5T_INTEGER) {
    throw InputError(path, full + " does not hold integers");
  }
  hsize_t dims[1] = {0};
  if (rank == 0) {
    dims[0] = 1;  // a scalar (t_offset)
  } else if (rank != 1 || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) {
    throw InputError(path, full + " is not a 1-D array (rank " + std::to_string(rank) + ")");
  }
  if (dims[0] == 0) throw InputError(path, full + " is empty");
  *length = static_cast<std::size_t>(dims[0]);

  Hid dcpl(H5Dget_create_plist(ds.get()), H5Pclose);
  const int nfilters = H5Pget_nfilters(dcpl.get());
  for (int i = 0; i < nfilters; ++i) {
    std::size_t nvalues = 0;
    unsigned flags = 0, config = 0;
    char filter_name[64] = {};
    const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), static_cast<unsigned>(i), &flags, &nvalues, nullptr,
                                           sizeof filter_name, filter_name, &config);
    if (id == hdf5::kZstdFilter) hdf5::registerZstdFilter();
    if (id < 0 || (id == kBloscFilter ? !loadBlosc() : H5Zfilter_avail(id) <= 0)) {
      throw InputError(path, full + " needs HDF5 filter " + std::to_string(id) + " ('" + filter_name +
                                 "'), which cannot be loaded" +
                                 (id == kBloscFilter ? ": install hdf5-filter-plugin-blosc-serial "
                                                       "or set HDF5_PLUGIN_PATH"
                                                     : ""));
    }
  }
  hsize_t chunk[1] = {0};
  if (H5Pget_layout(dcpl.get()) == H5D_CHUNKED && H5Pget_chunk(dcpl.get(), 1, chunk) == 1) {
    const std::size_t chunk_bytes = chunk[0] * H5Tget_size(type.get());
    const std::size_t cache = std::max<std::size_t>(std::size_t{1} << 20, 4 * chunk_bytes);
    Hid dapl(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
    H5Pset_chunk_cache(dapl.get(), H5D_CHUNK_CACHE_NSLOTS_DEFAULT, cache, 1.0);
    ds = Hid(H5Dopen2(file, name, dapl.get()), H5Dclose);
    if (!ds.valid()) failH5(path, "cannot open " + full);
  }
  return ds;
}

}  // namespace

struct Hdf5EventSource::Impl {
  std::string path;
  Hdf5EventOptions options;
  std::array<std::string, 4> names;  // group/t, group/x, group/y, group/p
  Hid file;
  std::array<Hid, 4> ds;
  std::array<Hid, 4> fspace;
  Hid dxpl;
  Hid ms_to_idx;
  std::size_t ms_count = 0;
  std::size_t n = 0;
  std::size_t pos = 0;
  std::int64_t t_offset = 0;  // in ticks of events/t
  std::int64_t tick_ns = 1000;
  std::int64_t prev_t = 0;  // last value read, for the ordering check across reads
  bool has_prev = false;
  bool p_unsigned = true;  // p read as raw uint8 bytes: only 0/1 are valid
  bool overflow = false;   // set by abortOnOverflow

  void readRange(Field f, hid_t memtype, void* buf, std::size_t start, std::size_t count) {
    const hsize_t s[1] = {start}, c[1] = {count};
    Hid mspace(H5Screate_simple(1, c, nullptr), H5Sclose);
    overflow = false;
    if (H5Sselect_hyperslab(fspace[f].get(), H5S_SELECT_SET, s, nullptr, c, nullptr) < 0 ||
        H5Dread(ds[f].get(), memtype, mspace.get(), fspace[f].get(), dxpl.get(), buf) < 0) {
      const std::string where =
          names[f] + "[" + std::to_string(start) + ".." + std::to_string(start + count) + ")";
      if (overflow) throw InputError(path, where + " holds a value out of range for its field");
      failH5(path, "cannot read " + where);
    }
  }

  std::int64_t tAt(std::size_t i) {
    std::int64_t v = 0;
    readRange(kT, H5T_NATIVE_INT64, &v, i, 1);
    return v;
  }

  std::size_t msToIdx(std::size_t i) {
    const hsize_t s[1] = {i}, c[1] = {1};
    Hid fs(H5Dget_space(ms_to_idx.get()), H5Sclose);
    Hid ms(H5Screate_simple(1, c, nullptr), H5Sclose);
    std::uint64_t v = 0;
    if (H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, s, nullptr, c, nullptr) < 0 ||
        H5Dread(ms_to_idx.get(), H5T_NATIVE_UINT64, ms.get(), fs.get(), dxpl.get(), &v) < 0) {
      failH5(path, "cannot read ms_to_idx[" + std::to_string(i) + "]");
    }
    if (v > n) {
      throw InputError(path, "ms_to_idx[" + std::to_string(i) + "] = " + std::to_string(v) +
                                 " is beyond the " + std::to_string(n) + " events");
    }
    return static_cast<std::size_t>(v);
  }

  const char* unit() const { return tick_ns == 1 ? " ns" : " us"; }

  TimeNs toNs(std::int64_t t) const {
    TimeNs sum = 0, ns = 0;
    if (__builtin_add_overflow(t, t_offset, &sum) || __builtin_mul_overflow(sum, tick_ns, &ns)) {
      throw InputError(path, "events/t = " + std::to_string(t) + " + t_offset overflows int64 ns");
    }
    return ns;
  }

  // Checks one block [old, old + count) of out and converts it in place. The checks are
  // branch-free reductions, so that the valid case runs without branches (and vectorizes where
  // the types allow); the offending index is only searched for once something is wrong.
  void checkAndConvert(EventArray& out, std::size_t old, std::size_t count) {
    std::int64_t* t = out.t.data() + old;
    // One pass checks the order and converts: 64-bit compares do not vectorize on baseline
    // x86-64, so a second pass over t would cost as much again. Unsigned arithmetic keeps a
    // wrap-around defined; it is ruled out below from the first and last values.
    const std::int64_t first = t[0];
    std::int64_t last = has_prev ? prev_t : first;
    const auto uoff = static_cast<std::uint64_t>(t_offset);
    const auto utick = static_cast<std::uint64_t>(tick_ns);
    unsigned bad = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const std::int64_t v = t[i];
      bad |= v < last;
      last = v;
      t[i] = static_cast<std::int64_t>((static_cast<std::uint64_t>(v) + uoff) * utick);
    }
    if (bad) reportOrder(t, count);  // t is overwritten: it re-reads the block from the file
    // Sorted, so the first and last values bound all: (t + offset) * tick must fit int64.
    const std::int64_t kMax = std::numeric_limits<std::int64_t>::max() / tick_ns;
    std::int64_t lo = 0, hi = 0;
    if (__builtin_add_overflow(first, t_offset, &lo) || __builtin_add_overflow(last, t_offset, &hi) ||
        lo < -kMax || hi > kMax) {
      throw InputError(path, "events/t[" + std::to_string(pos) + ".." + std::to_string(pos + count) +
                                 ") + t_offset overflows int64 ns");
    }
    prev_t = last;
    has_prev = true;

    if (options.width > 0) checkPixels(out.x.data() + old, count, options.width, kX);
    if (options.height > 0) checkPixels(out.y.data() + old, count, options.height, kY);

    std::int8_t* p = out.p.data() + old;
    bad = 0;
    if (p_unsigned) {
      for (std::size_t i = 0; i < count; ++i) bad |= static_cast<std::uint8_t>(p[i]) > 1;
    } else {
      for (std::size_t i = 0; i < count; ++i) bad |= static_cast<std::uint8_t>(p[i] + 1) > 2;
    }
    if (bad) {
      for (std::size_t i = 0; i < count; ++i) {
        const int v = p_unsigned ? static_cast<std::uint8_t>(p[i]) : p[i];
        if (v != 0 && v != 1 && v != -1) {
          throw InputError(path, "events/p[" + std::to_string(pos + i) + "] = " + std::to_string(v) +
                                     ": polarity must be 0/1 or -1/+1");
        }
      }
    }
    for (std::size_t i = 0; i < count; ++i) p[i] = static_cast<std::int8_t>(p[i] == 1 ? 1 : -1);
  }

  [[noreturn]] void reportOrder(std::int64_t* t, std::size_t count) {
    readRange(kT, H5T_NATIVE_INT64, t, pos, count);
    std::size_t i = (has_prev && t[0] < prev_t) ? 0 : 1;
    while (i < count && t[i] >= t[i - 1]) ++i;
    const std::int64_t before = i == 0 ? prev_t : t[i - 1];
    throw InputError(path, "events/t[" + std::to_string(pos + i) + "] = " + std::to_string(t[i]) + unit() +
                               " is before the previous event (" + std::to_string(before) + unit() +
                               "): timestamps must not decrease");
  }

  void checkPixels(const std::uint16_t* v, std::size_t count, int limit, Field f) const {
    if (limit > 65535) return;  // every uint16 fits
    const auto lim = static_cast<std::uint16_t>(limit);
    unsigned bad = 0;
    for (std::size_t i = 0; i < count; ++i) bad |= v[i] >= lim;
    if (!bad) return;
    std::size_t i = 0;
    while (v[i] < lim) ++i;
    throw InputError(path, names[f] + "[" + std::to_string(pos + i) + "] = " + std::to_string(v[i]) +
                               " is outside the sensor (" + (f == kX ? "width " : "height ") +
                               std::to_string(limit) + ")");
  }
};

Hdf5EventSource::Hdf5EventSource(const std::string& path, Hdf5EventOptions options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  m.options = options;
  m.tick_ns = options.tick_ns;
  if (m.tick_ns <= 0 || 1'000'000 % m.tick_ns != 0)
    throw std::invalid_argument("Hdf5EventSource: tick_ns must divide a millisecond");
  QuietHdf5 quiet;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "file does not exist");
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "not a regular file");
  if (H5Fis_hdf5(path.c_str()) <= 0) throw InputError(path, "not an HDF5 file");
  hdf5::addPluginPath();
  // HDF5 serves small reads of contiguous data through a 64 KiB sieve buffer, refilled on every
  // binary-search probe of seek(); bulk reads bypass it, so a small one costs nothing there.
  Hid fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_sieve_buf_size(fapl.get(), 4096);
  m.file = Hid(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (!m.file.valid()) failH5(path, "cannot open the HDF5 file");

  std::array<std::size_t, 4> lengths{};
  for (int f = 0; f < 4; ++f) {
    m.names[f] = m.options.group + "/" + kFieldNames[f];
    m.ds[f] = openDataset(m.file.get(), path, m.names[f].c_str(), &lengths[f]);
    m.fspace[f] = Hid(H5Dget_space(m.ds[f].get()), H5Sclose);
  }
  for (int f = 1; f < 4; ++f) {
    if (lengths[f] != lengths[0]) {
      throw InputError(path, m.names[f] + " has " + std::to_string(lengths[f]) + " elements but " +
                                 m.names[0] + " has " + std::to_string(lengths[0]));
    }
  }
  m.n = lengths[0];
  {
    Hid ptype(H5Dget_type(m.ds[kP].get()), H5Tclose);
    // A one-byte unsigned p (DSEC) is read raw, without a conversion pass; wider types are
    // converted to int8 by HDF5, which reports values that do not fit.
    m.p_unsigned = H5Tget_size(ptype.get()) == 1 && H5Tget_sign(ptype.get()) == H5T_SGN_NONE;
  }

  m.dxpl = Hid(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
  H5Pset_type_conv_cb(m.dxpl.get(), abortOnOverflow, &m.overflow);

  if (H5Lexists(m.file.get(), "t_offset", H5P_DEFAULT) > 0) {
    std::size_t len = 0;
    Hid ds = openDataset(m.file.get(), path, "t_offset", &len);
    if (len != 1) throw InputError(path, "t_offset has " + std::to_string(len) + " values, not 1");
    if (H5Dread(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, m.dxpl.get(), &m.t_offset) < 0) {
      failH5(path, "cannot read t_offset");
    }
  }
  if (H5Lexists(m.file.get(), m.options.ms_index.c_str(), H5P_DEFAULT) > 0) {
    m.ms_to_idx = openDataset(m.file.get(), path, m.options.ms_index.c_str(), &m.ms_count);
  }
}

Hdf5EventSource::~Hdf5EventSource() {
  QuietHdf5 quiet;  // closing must not print either
  impl_.reset();
}

std::size_t Hdf5EventSource::read(EventArray& out, std::size_t max_events) {
  Impl& m = *impl_;
  const std::size_t count = std::min(max_events, m.n - m.pos);
  if (count == 0) return 0;
  QuietHdf5 quiet;
  const std::size_t old = out.size();
  out.resize(old + count);
  try {
    // Memory types matching the usual file types let HDF5 copy without a conversion pass.
    m.readRange(kT, H5T_NATIVE_INT64, out.t.data() + old, m.pos, count);
    m.readRange(kX, H5T_NATIVE_UINT16, out.x.data() + old, m.pos, count);
    m.readRange(kY, H5T_NATIVE_UINT16, out.y.data() + old, m.pos, count);
    m.readRange(kP, m.p_unsigned ? H5T_NATIVE_UINT8 : H5T_NATIVE_INT8, out.p.data() + old, m.pos, count);
    m.checkAndConvert(out, old, count);
  } catch (...) {
    out.resize(old);  // leave out as it was
    throw;
  }
  m.pos += count;
  return count;
}

std::optional<std::size_t> Hdf5EventSource::size() const { return impl_->n; }
const std::vector<TriggerEvent>& Hdf5EventSource::triggers() const { return impl_->options.triggers; }
std::size_t Hdf5EventSource::position() const { return impl_->pos; }
TimeNs Hdf5EventSource::tOffsetNs() const { return impl_->t_offset * impl_->tick_ns; }
bool Hdf5EventSource::hasMsToIdx() const { return impl_->ms_to_idx.valid(); }
const std::string& Hdf5EventSource::path() const { return impl_->path; }

TimeNs Hdf5EventSource::firstTimeNs() const {
  QuietHdf5 quiet;
  return impl_->toNs(impl_->tAt(0));
}

TimeNs Hdf5EventSource::lastTimeNs() const {
  QuietHdf5 quiet;
  return impl_->toNs(impl_->tAt(impl_->n - 1));
}

void Hdf5EventSource::seekIndex(std::size_t index) {
  impl_->pos = std::min(index, impl_->n);
  impl_->has_prev = false;
}

void Hdf5EventSource::seek(TimeNs t_ns) {
  Impl& m = *impl_;
  QuietHdf5 quiet;
  // First event with (t + offset) * tick >= t_ns, i.e. t >= ceil(t_ns / tick) - offset (division
  // truncates toward zero, which is the ceiling for negative values). Saturates far out of range.
  std::int64_t target = 0;
  if (__builtin_sub_overflow(t_ns / m.tick_ns + (t_ns % m.tick_ns > 0), m.t_offset, &target)) {
    target =
        m.t_offset < 0 ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
  }
  std::size_t lo = 0, hi = m.n;
  const std::int64_t ticks_per_ms = 1'000'000 / m.tick_ns;
  if (m.ms_to_idx.valid()) {
    // ms_to_idx[i] <= answer <= ms_to_idx[i + 1] for target in [i ms, (i + 1) ms).
    if (target < 0) {
      hi = m.msToIdx(0);
    } else if (static_cast<std::uint64_t>(target / ticks_per_ms) + 1 < m.ms_count) {
      const auto i = static_cast<std::size_t>(target / ticks_per_ms);
      lo = m.msToIdx(i);
      hi = m.msToIdx(i + 1);
    } else {
      lo = m.msToIdx(m.ms_count - 1);
    }
    if (lo > hi) {
      throw InputError(m.path, "ms_to_idx decreases near " + std::to_string(target / ticks_per_ms) + " ms");
    }
  }
  // Probes narrow [lo, hi] down to a block that one read brings in: every HDF5 read has a fixed
  // cost of microseconds, so a dozen single-value probes would cost more than the block.
  constexpr std::size_t kBlock = 8192;
  while (hi - lo > kBlock) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (m.tAt(mid) < target) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  if (lo < hi) {
    std::vector<std::int64_t> block(hi - lo);
    m.readRange(kT, H5T_NATIVE_INT64, block.data(), lo, block.size());
    lo += static_cast<std::size_t>(std::lower_bound(block.begin(), block.end(), target) - block.begin());
  }
  m.pos = lo;
  m.has_prev = false;
}

bool hdf5BloscAvailable() {
  QuietHdf5 quiet;
  return loadBlosc();
}

}  // namespace eds
