// Uploads read only the upload (issue 14): the restricted open (maps::openUpload through
// maps::UploadSandbox) refuses VRTs, labels that point outside, nested datasets of refused drivers,
// symlinks out of the folder and every network path; zips work; errors are words without paths.
#include <doctest/doctest.h>

#include <arpa/inet.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/loopback_listener.hpp"
#include "core/common/error.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

struct Folder {
  fs::path path;
  Folder() {
    path = fs::temp_directory_path() / ("roverplan-sec-" + std::to_string(::getpid()) + "-" + std::to_string(std::rand()));
    fs::create_directories(path / "upload");
  }
  ~Folder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  // The staging folder an upload lands in.
  std::string root() const { return (path / "upload").string(); }
  std::string file(const std::string& name) const { return (path / "upload" / name).string(); }
};

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A 20 × 30 GeoTIFF of 1 m cells on UTM 33N with a gentle slope.
void writeSmallTiff(const std::string& path) {
  Raster<float> z(GridGeometry{20, 30, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 20; ++r)
    for (int c = 0; c < 30; ++c) z(r, c) = 0.1f * c + 0.05f * r;
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100020, 0, -1};
  maps::writeGeoTiff(path, z);
}

struct Outcome {
  bool ok = false;
  std::string message, field;
};

// loadDem of `path` as an upload of the folder `root`.
Outcome loadAsUpload(const std::string& root, const std::string& path, maps::LoadOptions o = {}) {
  maps::UploadSandbox sandbox(root);
  o.upload = &sandbox;
  Outcome out;
  try {
    maps::loadDem(path, o);
    out.ok = true;
  } catch (const Error& e) {
    out.message = e.what();
    out.field = e.field();
  }
  return out;
}

// The message names no server folder: neither the upload's folder nor any absolute path.
void checkNoPaths(const Outcome& r, const Folder& f) {
  CHECK_MESSAGE(r.message.find(f.path.string()) == std::string::npos, r.message);
  CHECK_MESSAGE(r.message.find("/tmp") == std::string::npos, r.message);
  CHECK_MESSAGE(r.message.find("/etc") == std::string::npos, r.message);
  CHECK_MESSAGE(r.message.find("/vsi") == std::string::npos, r.message);
}

const char* kPasswdVrt = R"(<VRTDataset rasterXSize="32" rasterYSize="8">
  <VRTRasterBand dataType="Byte" band="1" subClass="VRTRawRasterBand">
    <SourceFilename relativetoVRT="0">/etc/passwd</SourceFilename>
    <ImageOffset>0</ImageOffset><PixelOffset>1</PixelOffset><LineOffset>32</LineOffset>
  </VRTRasterBand>
</VRTDataset>
)";

// A PDS3 label for an 8 × 32 byte image stored in `image` (a detached label).
std::string pds3Label(const std::string& image) {
  return "PDS_VERSION_ID = PDS3\r\nRECORD_TYPE = FIXED_LENGTH\r\nRECORD_BYTES = 32\r\nFILE_RECORDS = 8\r\n"
         "^IMAGE = (\"" + image + "\", 1)\r\nOBJECT = IMAGE\r\n  LINES = 8\r\n  LINE_SAMPLES = 32\r\n"
         "  SAMPLE_TYPE = UNSIGNED_INTEGER\r\n  SAMPLE_BITS = 8\r\nEND_OBJECT = IMAGE\r\nEND\r\n";
}

using rover::test::Listener;

}  // namespace

TEST_CASE("dem security: a VRT whose source is /etc/passwd is refused, named as uploaded") {
  Folder f;
  writeText(f.file("passwd.vrt"), kPasswdVrt);
  Outcome r = loadAsUpload(f.root(), f.file("passwd.vrt"));
  CHECK_FALSE(r.ok);
  CHECK(r.field == "file");
  CHECK_MESSAGE(r.message.find("passwd.vrt") == 0, r.message);
  CHECK_MESSAGE(r.message.find("VRT") != std::string::npos, r.message);
  CHECK_MESSAGE(r.message.find("root:") == std::string::npos, r.message);
  checkNoPaths(r, f);
  // The command line trusts its own files: the same VRT still opens there.
  maps::ensureGdal();
  GDALDatasetH ds = GDALOpen(f.file("passwd.vrt").c_str(), GA_ReadOnly);
  CHECK(ds != nullptr);
  if (ds) GDALClose(ds);
}

TEST_CASE("dem security: a PDS3 label whose ^IMAGE points outside the upload is refused") {
  Folder f;
  writeText(f.file("evil.lbl"), pds3Label("../../../../../../../../../etc/passwd"));
  Outcome r = loadAsUpload(f.root(), f.file("evil.lbl"));
  CHECK_FALSE(r.ok);
  CHECK_MESSAGE(r.message.find("evil.lbl refers to 'passwd'") == 0, r.message);
  CHECK_MESSAGE(r.message.find("not part of the upload") != std::string::npos, r.message);
  checkNoPaths(r, f);

  // The same through a symlink inside the folder (canonical paths are compared).
  fs::create_symlink("/etc/passwd", f.file("link.img"));
  writeText(f.file("linked.lbl"), pds3Label("link.img"));
  r = loadAsUpload(f.root(), f.file("linked.lbl"));
  CHECK_FALSE(r.ok);
  CHECK_MESSAGE(r.message.find("not part of the upload") != std::string::npos, r.message);
  checkNoPaths(r, f);

  // Another map's folder next to the upload is outside too.
  fs::create_directories(f.path / "other");
  writeText((f.path / "other" / "secret.img").string(), std::string(256, 'x'));
  writeText(f.file("sibling.lbl"), pds3Label("../other/secret.img"));
  r = loadAsUpload(f.root(), f.file("sibling.lbl"));
  CHECK_MESSAGE(r.message.find("sibling.lbl refers to 'secret.img'") == 0, r.message);

  // A label whose image is in the upload opens.
  writeText(f.file("good.img"), std::string(256, '\x05'));
  writeText(f.file("good.lbl"), pds3Label("good.img"));
  r = loadAsUpload(f.root(), f.file("good.lbl"));
  CHECK_MESSAGE(r.ok, r.message);
}

TEST_CASE("dem security: a dataset nested in an allowed one cannot use a refused driver") {
  // An ISIS3 cube whose external core is a VRT reading /etc/passwd: GDAL lists only the label in
  // GetFileList, so only the driver gate stops it.
  Folder f;
  writeText(f.file("core.vrt"), kPasswdVrt);
  writeText(f.file("cube.lbl"),
            "Object = IsisCube\n  Object = Core\n    ^Core = \"core.vrt\"\n    Format = GeoTIFF\n"
            "    Group = Dimensions\n      Samples = 32\n      Lines = 8\n      Bands = 1\n    End_Group\n"
            "    Group = Pixels\n      Type = UnsignedByte\n      ByteOrder = Lsb\n      Base = 0.0\n"
            "      Multiplier = 1.0\n    End_Group\n  End_Object\nEnd_Object\nEnd\n");
  Outcome r = loadAsUpload(f.root(), f.file("cube.lbl"));
  CHECK_FALSE(r.ok);
  CHECK_MESSAGE(r.message.find("cube.lbl") == 0, r.message);
  CHECK_MESSAGE(r.message.find("root:") == std::string::npos, r.message);
  checkNoPaths(r, f);
}

TEST_CASE("dem security: network paths are refused without any connection") {
  maps::ensureGdal();
  Listener server;
  const std::string url = "http://127.0.0.1:" + std::to_string(server.port) + "/dem.tif";
  // Process-wide: /vsicurl/ and GDAL's HTTP client are off, also outside any upload.
  VSIStatBufL st;
  CHECK(VSIStatL(("/vsicurl/" + url).c_str(), &st) != 0);
  CHECK(GDALOpen(("/vsicurl/" + url).c_str(), GA_ReadOnly) == nullptr);
  CHECK(GDALOpen(url.c_str(), GA_ReadOnly) == nullptr);  // the HTTP driver
  const std::string wms = "<GDAL_WMS><Service name=\"TMS\"><ServerUrl>http://127.0.0.1:" +
                          std::to_string(server.port) + "/${z}/${x}/${y}.png</ServerUrl></Service>"
                          "<DataWindow><UpperLeftX>0</UpperLeftX><UpperLeftY>1</UpperLeftY><LowerRightX>1</LowerRightX>"
                          "<LowerRightY>0</LowerRightY><SizeX>256</SizeX><SizeY>256</SizeY></DataWindow>"
                          "<BandsCount>1</BandsCount></GDAL_WMS>";
  CHECK(GDALOpen(wms.c_str(), GA_ReadOnly) == nullptr);  // network drivers are off
  // In an upload: a /vsicurl/ path is not a file of the upload; a label pointing at one is refused.
  Folder f;
  {
    maps::UploadSandbox sandbox(f.root());
    std::string refusal;
    CHECK(maps::openUpload("/vsicurl/" + url, sandbox, refusal) == nullptr);
    CHECK_MESSAGE(refusal.find("not a file of the upload") != std::string::npos, refusal);
    CHECK(refusal.find("127.0.0.1") == std::string::npos);
  }
  writeText(f.file("net.lbl"), pds3Label("/vsicurl/" + url));
  Outcome r = loadAsUpload(f.root(), f.file("net.lbl"));
  CHECK_FALSE(r.ok);
  checkNoPaths(r, f);
  CHECK(server.connections(200) == 0);
}

TEST_CASE("dem security: a zip holding a GeoTIFF, and one holding a PDS3 .IMG + .LBL pair, load") {
  Folder f;
  const std::string tif = (f.path / "dem.tif").string();
  writeSmallTiff(tif);
  // GDAL writes zips itself: each member through /vsizip/ARCHIVE/NAME.
  auto addToZip = [](const std::string& zip, const std::string& member, const std::string& bytes) {
    VSILFILE* out = VSIFOpenL(("/vsizip/" + zip + "/" + member).c_str(), "wb");
    REQUIRE(out);
    CHECK(VSIFWriteL(bytes.data(), 1, bytes.size(), out) == bytes.size());
    VSIFCloseL(out);
  };
  addToZip(f.file("dem.zip"), "dem.tif", readBytes(tif));
  Outcome r = loadAsUpload(f.root(), "/vsizip/" + f.file("dem.zip") + "/dem.tif");
  CHECK_MESSAGE(r.ok, r.message);
  // The trusted path opens archive members too (it checked them with std::filesystem before).
  CHECK(maps::loadDem("/vsizip/" + f.file("dem.zip") + "/dem.tif").dem.geometry().cols == 30);

  std::string image;
  for (int i = 0; i < 8 * 32; ++i) image += static_cast<char>(i % 50);
  addToZip(f.file("pds.zip"), "PAIR.LBL", pds3Label("PAIR.IMG"));
  addToZip(f.file("pds.zip"), "PAIR.IMG", image);
  maps::UploadSandbox sandbox(f.root());
  maps::LoadOptions o;
  o.upload = &sandbox;
  maps::LoadedDem d = maps::loadDem("/vsizip/" + f.file("pds.zip") + "/PAIR.LBL", o);
  CHECK(d.info.driver == "PDS");
  CHECK(d.dem.geometry().cols == 32);
  CHECK(d.dem.z(0, 5) == doctest::Approx(5));
  CHECK(d.info.path == "pds.zip/PAIR.LBL");
  // The member .IMG on its own finds its label next to it.
  CHECK(maps::loadDem("/vsizip/" + f.file("pds.zip") + "/PAIR.IMG", o).info.driver == "PDS");
  CHECK(sandbox.refusedFiles().empty());
}

TEST_CASE("dem security: a valid upload opens without reaching outside its folder") {
  Folder f;
  writeSmallTiff(f.file("ok.tif"));
  writeText(f.file("ok.tif.aux.xml"), "<PAMDataset><Metadata><MDI key=\"NOTE\">inside</MDI></Metadata></PAMDataset>");
  maps::UploadSandbox sandbox(f.root());
  maps::LoadOptions o;
  o.upload = &sandbox;
  o.cellSize = 2;  // through the warper too
  maps::LoadedDem d = maps::loadDem(f.file("ok.tif"), o);
  CHECK(d.dem.geometry().cols == 15);
  CHECK_MESSAGE(sandbox.refusedFiles().empty(), sandbox.refusedFiles().front());
  CHECK(sandbox.refusedDrivers().empty());
  CHECK(sandbox.contains(f.file("ok.tif")));
  CHECK_FALSE(sandbox.contains("/etc/passwd"));
  CHECK_FALSE(sandbox.contains(f.root() + "/../x.tif"));
  CHECK_FALSE(sandbox.contains("/vsizip/" + f.file("a.zip") + "/../../x"));
  CHECK_FALSE(sandbox.contains("/vsisubfile/0_10," + f.file("ok.tif")));
}

TEST_CASE("dem security: errors are words without server paths") {
  Folder f;
  const std::string tif = f.file("full.tif");
  writeSmallTiff(tif);
  const std::string bytes = readBytes(tif);

  // A GeoTIFF cut short: its header reads, its data does not — or not even the header.
  writeText(f.file("cut.tif"), bytes.substr(0, bytes.size() - 200));
  Outcome r = loadAsUpload(f.root(), f.file("cut.tif"));
  CHECK_MESSAGE(r.message.rfind("cut.tif: truncated or corrupt GeoTIFF", 0) == 0, r.message);
  checkNoPaths(r, f);
  writeText(f.file("head.tif"), bytes.substr(0, 60));
  r = loadAsUpload(f.root(), f.file("head.tif"));
  CHECK_MESSAGE(r.message == "head.tif: truncated or corrupt GeoTIFF", r.message);

  // A PDS3 .IMG without its .LBL.
  writeText(f.file("LONE.IMG"), std::string(4096, '\x01'));
  r = loadAsUpload(f.root(), f.file("LONE.IMG"));
  CHECK_MESSAGE(r.message.find("LONE.IMG: the label is missing") == 0, r.message);
  CHECK(r.message.find(".LBL") != std::string::npos);

  // A cell size larger than the map (30 × 20 m).
  maps::LoadOptions o;
  o.cellSize = 500;
  r = loadAsUpload(f.root(), f.file("full.tif"), o);
  CHECK(r.field == "cell");
  CHECK_MESSAGE(r.message.find("larger than the map") != std::string::npos, r.message);
  CHECK(r.message.find("30 x 20 m") != std::string::npos);
  checkNoPaths(r, f);

  // Not a raster at all.
  writeText(f.file("notes.tif"), "just some text, not a raster");
  r = loadAsUpload(f.root(), f.file("notes.tif"));
  CHECK_MESSAGE(r.message.find("notes.tif: not a raster format roverplan reads") == 0, r.message);

  // Over the source budget: a tiny file that declares a huge raster is refused before reading.
  o = {};
  o.maxCells = 100;
  r = loadAsUpload(f.root(), f.file("full.tif"), o);
  CHECK(r.field == "max_cells");
  checkNoPaths(r, f);

  CHECK(maps::withoutPaths("cannot open /tmp/x/y/dem.tif, see /vsizip//a/b.zip/c.img") ==
        "cannot open dem.tif, see c.img");
}

namespace {

// An ENVI header for a `rows` × `cols` int16 raster on UTM 33N.
std::string enviHeader(int rows, int cols, const std::string& offset = "0") {
  return "ENVI\nsamples = " + std::to_string(cols) + "\nlines = " + std::to_string(rows) +
         "\nbands = 1\nheader offset = " + offset +
         "\nfile type = ENVI Standard\ndata type = 2\ninterleave = bsq\nbyte order = 0\n"
         "map info = {UTM, 1, 1, 500000, 4000000, 1, 1, 33, North, WGS-84}\n";
}

}  // namespace

TEST_CASE("dem security: a raw raster whose data file is shorter than its header says is refused") {
  Folder f;
  // A 20 × 30 int16 ENVI raster with all its data loads.
  writeText(f.file("ok.hdr"), enviHeader(20, 30));
  writeText(f.file("ok.bin"), std::string(20 * 30 * 2, '\x10'));
  Outcome r = loadAsUpload(f.root(), f.file("ok.bin"));
  CHECK_MESSAGE(r.ok, r.message);

  // The tester's upload: 17 100 bytes of data, a header that says 7000 × 7000 (98 MB).
  writeText(f.file("x.hdr"), enviHeader(7000, 7000));
  writeText(f.file("x.bin"), std::string(17100, '\x10'));
  r = loadAsUpload(f.root(), f.file("x.bin"));
  CHECK_FALSE(r.ok);
  CHECK(r.field == "file");
  CHECK_MESSAGE(r.message == "x.bin: x.hdr describes 7000 × 7000 cells but x.bin holds only 17 KB: truncated or "
                             "mismatched",
                r.message);
  checkNoPaths(r, f);

  // One byte short of a 20 × 30 raster.
  writeText(f.file("short.hdr"), enviHeader(20, 30));
  writeText(f.file("short.bin"), std::string(20 * 30 * 2 - 1, '\x10'));
  r = loadAsUpload(f.root(), f.file("short.bin"));
  CHECK_MESSAGE(r.message.find("short.hdr describes 20 × 30 cells but short.bin holds only 1199 bytes") !=
                    std::string::npos,
                r.message);

  // A header offset far past the end of the file: every cell would read as 0.
  writeText(f.file("far.hdr"), enviHeader(20, 30, "99999999999"));
  writeText(f.file("far.bin"), std::string(20 * 30 * 2, '\x10'));
  r = loadAsUpload(f.root(), f.file("far.bin"));
  CHECK_FALSE(r.ok);
  CHECK_MESSAGE(r.message.find("truncated or mismatched") != std::string::npos, r.message);
  checkNoPaths(r, f);

  // The same for an ESRI .hdr/.bil pair.
  writeText(f.file("e.hdr"), "NROWS 500\nNCOLS 400\nNBITS 16\nPIXELTYPE SIGNEDINT\nBYTEORDER I\n"
                             "ULXMAP 0.5\nULYMAP 499.5\nXDIM 1\nYDIM 1\n");
  writeText(f.file("e.bil"), std::string(1000, '\x01'));
  r = loadAsUpload(f.root(), f.file("e.bil"));
  CHECK_MESSAGE(r.message.find("e.hdr describes 500 × 400 cells but e.bil holds only 1000 bytes") != std::string::npos,
                r.message);

  // A Surfer 6 binary grid (56-byte header, float32 cells) cut short.
  std::string grd = "DSBB";
  auto put = [&grd](const void* p, std::size_t n) { grd.append(static_cast<const char*>(p), n); };
  const std::int16_t nx = 300, ny = 200;
  const double bounds[6] = {0, 299, 0, 199, 0, 1};
  put(&nx, 2);
  put(&ny, 2);
  put(bounds, sizeof bounds);
  grd += std::string(1000, '\0');
  writeText(f.file("s.grd"), grd);
  r = loadAsUpload(f.root(), f.file("s.grd"));
  CHECK_FALSE(r.ok);
  CHECK_MESSAGE(r.message.find("s.grd describes 200 × 300 cells but s.grd holds only") != std::string::npos,
                r.message);
}

TEST_CASE("dem security: a tiny GeoTIFF declaring huge sparse tiles is refused before any read") {
  // Found by fuzz_dem_ingest: an 8 × 8 GeoTIFF of 674 bytes with 16384 × 16384 sparse tiles of 64
  // pixel-interleaved Float64 bands made GDAL calloc the whole 137 GB tile on the first read.
  Folder f;
  maps::ensureGdal();
  const char* options[] = {"TILED=YES", "BLOCKXSIZE=16384", "BLOCKYSIZE=16384", "SPARSE_OK=TRUE",
                           "INTERLEAVE=PIXEL", nullptr};
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), f.file("bomb.tif").c_str(), 8, 8, 64,
                               GDT_Float64, const_cast<char**>(options));
  REQUIRE(ds);
  GDALClose(ds);
  CHECK(fs::file_size(f.file("bomb.tif")) < 4096);
  Outcome r = loadAsUpload(f.root(), f.file("bomb.tif"));
  CHECK_FALSE(r.ok);
  CHECK(r.field == "file");
  CHECK_MESSAGE(r.message.find("bomb.tif: its blocks of 16384 × 16384 cells × 64 bands") == 0, r.message);
  CHECK_MESSAGE(r.message.find("too large to read") != std::string::npos, r.message);
  checkNoPaths(r, f);

  // A legitimately tiled GeoTIFF whose 256 × 256 tiles are larger than its 20 × 30 raster loads.
  const char* tiled[] = {"TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256", nullptr};
  ds = GDALCreate(GDALGetDriverByName("GTiff"), f.file("tiled.tif").c_str(), 30, 20, 1, GDT_Float32,
                  const_cast<char**>(tiled));
  REQUIRE(ds);
  std::vector<float> z(20 * 30, 5.0f);
  CHECK(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 30, 20, z.data(), 30, 20, GDT_Float32, 0,
                     0) == CE_None);
  GDALClose(ds);
  r = loadAsUpload(f.root(), f.file("tiled.tif"));
  CHECK_MESSAGE(r.ok, r.message);
}
