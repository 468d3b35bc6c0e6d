#!/usr/bin/env bash
# Installs everything rfd needs to build, test, benchmark and run its demo, from Debian 12
# packages only. Idempotent: it does nothing when every package is already installed.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  # clang and its sanitizer runtimes: the ASan+UBSan build (the asan preset; a second
  # compiler's warnings) and the libFuzzer build (the fuzz preset).
  clang libclang-rt-dev
  libeigen3-dev libcgal-dev libtbb-dev
  libopenimageio-dev openimageio-tools libcairo2-dev
  # OpenEXR's own library: the EXR files most commands read and write, without loading
  # OpenImageIO's 260 libraries (core/exr_file.hpp).
  libopenexr-dev
  # The font of procedural letter fields and sheet labels (patterns/glyphs.cpp).
  fonts-dejavu-core
  # OpenCV's photo module: HDR assembly (Robertson et al. 2003). Its headers also satisfy
  # a path Debian's OpenImageIO CMake config insists on (/usr/include/opencv4).
  libopencv-photo-dev
  # OpenCV's imgproc: connected components of mirror-sphere highlights (relight/calibration).
  libopencv-imgproc-dev
  # OpenCV's video module: Farneback optical flow carrying highlights between light
  # directions when upsampling a field (relight/upsample, thesis 6.3.1).
  libopencv-video-dev
  # nanoflann: the k-d tree of intensity-normalised image windows searched by upsampling's
  # image-based priors (relight/image_priors, thesis 6.4.2).
  libnanoflann-dev
  # Embree 3: ray intersection for the virtual light stage (relight/ray_scene.cpp).
  libembree-dev
  # NLopt: COBYLA, the derivative-free constrained optimiser of `rfd design tune`.
  libnlopt-cxx-dev
  libtomlplusplus-dev libcli11-dev nlohmann-json3-dev
  # xxHash: content hashes of rfd make's manifest, fast enough to re-hash a pattern each run.
  libxxhash-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  openscad gnuplot-nox
  # pdftoppm and pdftocairo: the test that a PDF sheet's tile joins do not show renders it
  # as viewers do (tests/test_print.cpp).
  poppler-utils
  # three.js: the holder's 3D view on rfd make's preview page, vendored into each output.
  libjs-three
  # Headless Chromium: the preview page's browser test (tests/cli/preview.sh).
  chromium
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
