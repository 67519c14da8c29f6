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
