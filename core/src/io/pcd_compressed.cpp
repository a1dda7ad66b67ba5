// PCD DATA binary_compressed bodies through PCL's reader (PCDReader::readBodyBinary: LZF, then each
// field's values back into point records). Our header parser has already read the header (PCL's skips
// the comments that carry a glimpse sensor or frame); every size PCL trusts is checked here first, since
// PCL sizes its buffers from the body's own numbers.
#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include "io/text.h"

namespace glimpse::io_detail {
namespace {

// Each field's PCL type (pcl::PCLPointField datatype), or an error for a SIZE/TYPE PCL has none for.
Expected<std::vector<uint8_t>> pcl_types(const std::string& path, size_t start, const std::vector<PcdField>& fields) {
  std::vector<uint8_t> types;
  for (const PcdField& f : fields) {
    const int datatype = pcl::getFieldType(int(f.size), f.type);
    if (datatype < 0)
      return byte_error(path, start, "binary_compressed field '" + f.name + "' has SIZE " + std::to_string(f.size) +
                                         " TYPE " + f.type + ", which PCL cannot read");
    types.push_back(uint8_t(datatype));
  }
  return types;
}

// The cloud PCL's body reader fills: the header's fields, `points` records in one row.
pcl::PCLPointCloud2 pcl_layout(const std::vector<PcdField>& fields, const std::vector<uint8_t>& types, uint64_t points,
                               uint64_t record_bytes) {
  pcl::PCLPointCloud2 cloud;
  for (size_t k = 0; k < fields.size(); ++k) {
    pcl::PCLPointField field;
    field.name = fields[k].name;
    field.offset = uint32_t(fields[k].offset);
    field.datatype = types[k];
    field.count = uint32_t(fields[k].count);
    cloud.fields.push_back(field);
  }
  cloud.width = uint32_t(points);
  cloud.height = 1;
  cloud.point_step = uint32_t(record_bytes);
  cloud.row_step = uint32_t(points * record_bytes);
  cloud.data.resize(points * record_bytes);
  return cloud;
}

}  // namespace

Expected<std::string> read_compressed_body(const std::string& path, std::string_view text, size_t start,
                                           const std::vector<PcdField>& fields, uint64_t points, uint64_t record_bytes) {
  if (record_bytes > 0 && points > std::numeric_limits<uint32_t>::max() / record_bytes)
    return byte_error(path, start, "binary_compressed body of " + std::to_string(points) + " points of " +
                                       std::to_string(record_bytes) + " bytes: more than PCL reads (4 GiB)");
  const uint64_t expected = points * record_bytes, available = text.size() - start;
  if (expected == 0) return std::string();  // an empty cloud: PCL writes no body, or sizes of 0
  if (available < 8)
    return byte_error(path, start, "binary_compressed body truncated: " + std::to_string(available) +
                                       " bytes where its two sizes take 8");
  uint32_t compressed = 0, uncompressed = 0;
  std::memcpy(&compressed, text.data() + start, 4);
  std::memcpy(&uncompressed, text.data() + start + 4, 4);
  if (uncompressed != expected)
    return byte_error(path, start, "binary_compressed body unpacks to " + std::to_string(uncompressed) +
                                       " bytes, but POINTS and the fields' sizes say " + std::to_string(expected));
  if (compressed > available - 8)
    return byte_error(path, start, "binary_compressed body truncated: " + std::to_string(compressed) +
                                       " compressed bytes declared, " + std::to_string(available - 8) + " in the file");
  if (compressed == 0 || expected > kLzfMaxExpansion * compressed)
    return byte_error(path, start, "binary_compressed body of " + std::to_string(compressed) +
                                       " bytes cannot unpack to " + std::to_string(expected));
  // PCL reports a corrupt body on stderr as well as in its result; a service's log is no place for it.
  static const bool quiet = [] {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    return true;
  }();
  (void)quiet;
  const auto types = pcl_types(path, start, fields);
  if (!types) return types.error();
  pcl::PCLPointCloud2 cloud;
  int result = -1;
  try {
    cloud = pcl_layout(fields, *types, points, record_bytes);
    pcl::PCDReader reader;
    result = reader.readBodyBinary(reinterpret_cast<const unsigned char*>(text.data() + start), cloud, 7,
                                   /*compressed=*/true, 0);
  } catch (const std::bad_alloc&) {
    return resource_exhausted(path + ": out of memory while reading");
  } catch (const std::exception& e) {  // pcl::PCLException among them
    return byte_error(path, start, std::string("binary_compressed body: ") + e.what());
  }
  if (result < 0 || cloud.data.size() != expected)
    return byte_error(path, start, "binary_compressed body is corrupt: its LZF data does not unpack to " +
                                       std::to_string(expected) + " bytes");
  return std::string(reinterpret_cast<const char*>(cloud.data.data()), cloud.data.size());
}

}  // namespace glimpse::io_detail
