# Finds the OpenCV modules lsgd needs and defines the INTERFACE target
# lsgd_opencv. Debian ships OpenCVConfig.cmake only in the meta package
# libopencv-dev (which pulls in ~150 packages: Qt, VTK, ffmpeg); the per-module
# -dev packages we install ship headers and libraries only, so fall back to
# locating those directly.
set(_lsgd_cv_modules core imgproc imgcodecs features2d calib3d ${LSGD_EXTRA_OPENCV_MODULES})

if(NOT TARGET lsgd_opencv)
  find_package(OpenCV QUIET COMPONENTS ${_lsgd_cv_modules})
  add_library(lsgd_opencv INTERFACE IMPORTED)
  if(OpenCV_FOUND)
    set_target_properties(lsgd_opencv PROPERTIES
      INTERFACE_LINK_LIBRARIES "${OpenCV_LIBS}"
      INTERFACE_INCLUDE_DIRECTORIES "${OpenCV_INCLUDE_DIRS}")
  else()
    find_path(LSGD_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
    if(NOT LSGD_OPENCV_INCLUDE_DIR)
      message(FATAL_ERROR "OpenCV headers not found: run scripts/install-deps.sh")
    endif()
    set(_libs)
    foreach(m IN LISTS _lsgd_cv_modules)
      find_library(LSGD_OPENCV_${m}_LIBRARY opencv_${m})
      if(NOT LSGD_OPENCV_${m}_LIBRARY)
        message(FATAL_ERROR "OpenCV module opencv_${m} not found: run scripts/install-deps.sh")
      endif()
      list(APPEND _libs ${LSGD_OPENCV_${m}_LIBRARY})
    endforeach()
    set_target_properties(lsgd_opencv PROPERTIES
      INTERFACE_LINK_LIBRARIES "${_libs}"
      INTERFACE_INCLUDE_DIRECTORIES "${LSGD_OPENCV_INCLUDE_DIR}")
  endif()
endif()

# Optional: OpenCV's contrib module ximgproc (Debian: libopencv-contrib-dev),
# used only by the command-line tool, whose `lsgd bench` times OpenCV's own
# SLIC next to ours. When found, the INTERFACE target lsgd_opencv_ximgproc
# links it and defines LSGD_HAVE_XIMGPROC; never linked into the libraries.
if(LSGD_BUILD_TOOLS)
  option(LSGD_WITH_XIMGPROC "lsgd bench: also time OpenCV's SLIC (opencv_ximgproc) when found" ON)
endif()
if(LSGD_BUILD_TOOLS AND LSGD_WITH_XIMGPROC AND NOT TARGET lsgd_opencv_ximgproc)
  if(OpenCV_FOUND AND TARGET opencv_ximgproc)
    add_library(lsgd_opencv_ximgproc INTERFACE IMPORTED)
    set_target_properties(lsgd_opencv_ximgproc PROPERTIES
      INTERFACE_LINK_LIBRARIES opencv_ximgproc
      INTERFACE_COMPILE_DEFINITIONS LSGD_HAVE_XIMGPROC)
  else()
    find_path(LSGD_OPENCV_XIMGPROC_INCLUDE_DIR opencv2/ximgproc.hpp
      HINTS ${OpenCV_INCLUDE_DIRS} ${LSGD_OPENCV_INCLUDE_DIR} PATH_SUFFIXES opencv4)
    find_library(LSGD_OPENCV_ximgproc_LIBRARY opencv_ximgproc)
    if(LSGD_OPENCV_XIMGPROC_INCLUDE_DIR AND LSGD_OPENCV_ximgproc_LIBRARY)
      add_library(lsgd_opencv_ximgproc INTERFACE IMPORTED)
      set_target_properties(lsgd_opencv_ximgproc PROPERTIES
        INTERFACE_LINK_LIBRARIES "${LSGD_OPENCV_ximgproc_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${LSGD_OPENCV_XIMGPROC_INCLUDE_DIR}"
        INTERFACE_COMPILE_DEFINITIONS LSGD_HAVE_XIMGPROC)
    endif()
  endif()
  if(TARGET lsgd_opencv_ximgproc)
    message(STATUS "lsgd: opencv_ximgproc found: lsgd bench times OpenCV's SLIC")
  else()
    message(STATUS "lsgd: opencv_ximgproc not found: lsgd bench runs without OpenCV's SLIC "
                   "(install libopencv-contrib-dev)")
  endif()
elseif(LSGD_BUILD_TOOLS AND NOT LSGD_WITH_XIMGPROC)
  message(STATUS "lsgd: LSGD_WITH_XIMGPROC=OFF: lsgd bench runs without OpenCV's SLIC")
endif()
