"""The benchmarks' generated DEM (issue 24): deterministic terrain of any size made with GDAL's
command-line tools alone, shared by big_map.py and pdm_window.py.

Three octaves of seeded random heights on small grids (Python's random, seed 24, written as raw
float32 with an EHdr header), summed at full size by a VRT's built-in "sum" pixel function with
cubic-spline resampling, and written as a tiled DEFLATE GeoTIFF (1 m cells, a UTM CRS)."""
import os, random, struct, subprocess


def octave(path, cols, rows, amplitude, rng):
    """A cols x rows grid of seeded random heights in [-amplitude, amplitude] as EHdr float32."""
    with open(path + ".bil", "wb") as f:
        for _ in range(rows):
            f.write(struct.pack(f"<{cols}f", *(amplitude * (2 * rng.random() - 1) for _ in range(cols))))
    with open(path + ".hdr", "w") as f:
        f.write(f"NROWS {rows}\nNCOLS {cols}\nNBANDS 1\nNBITS 32\nPIXELTYPE FLOAT\nBYTEORDER I\n")


def make_dem(work, cols, rows):
    rng = random.Random(24)
    sources = []
    for i, (div, amp) in enumerate(((200, 60.0), (25, 6.0), (6, 0.4))):
        w, h = max(2, cols // div), max(2, rows // div)
        base = os.path.join(work, f"oct{i}")
        octave(base, w, h, amp, rng)
        sources.append(f"""<SimpleSource resampling="cubicspline"><SourceFilename relativeToVRT="1">oct{i}.bil</SourceFilename>
<SourceBand>1</SourceBand><SrcRect xOff="0" yOff="0" xSize="{w}" ySize="{h}"/>
<DstRect xOff="0" yOff="0" xSize="{cols}" ySize="{rows}"/></SimpleSource>""")
    vrt = os.path.join(work, "dem.vrt")
    with open(vrt, "w") as f:
        f.write(f"""<VRTDataset rasterXSize="{cols}" rasterYSize="{rows}">
<GeoTransform>500000, 1, 0, 4000000, 0, -1</GeoTransform>
<VRTRasterBand dataType="Float32" band="1" subClass="VRTDerivedRasterBand">
<PixelFunctionType>sum</PixelFunctionType>{''.join(sources)}</VRTRasterBand></VRTDataset>""")
    out = os.path.join(work, f"dem-{cols}x{rows}.tif")
    subprocess.run(["gdal_translate", "-q", "-a_srs", "EPSG:32633", "-co", "TILED=YES", "-co", "COMPRESS=DEFLATE",
                    "-co", "PREDICTOR=3", "-co", "BIGTIFF=IF_SAFER", "-co", "NUM_THREADS=ALL_CPUS", vrt, out],
                   check=True)
    return out
