#pragma once
// The part of the OpenHaptics HD API (3D Systems) this program calls, declared here because the
// vendor's headers may not be redistributed. Values as the runtime uses them (libHD.so); types
// as its ABI passes them on x86-64.

namespace vox::haptics::hd {

using HHD = unsigned int;
using HDenum = unsigned int;
using HDerror = unsigned int;
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
using HDSchedulerCallback = HDCallbackCode (*)(void* user);

struct HDErrorInfo {
    int errorCode;
    int internalErrorCode;
    HHD hHD;
};

constexpr HDerror HD_SUCCESS = 0;
constexpr HHD HD_INVALID_HANDLE = 0xFFFFFFFF;
constexpr HDenum HD_CURRENT_BUTTONS = 0x2000;
constexpr HDenum HD_CURRENT_POSITION = 0x2050;
constexpr HDenum HD_CURRENT_VELOCITY = 0x2051;
constexpr HDenum HD_CURRENT_TRANSFORM = 0x2052; ///< 16 doubles, column-major; translation in 12-14 (mm)
constexpr HDenum HD_DEVICE_MODEL_TYPE = 0x2501;
constexpr HDenum HD_DEVICE_SERIAL_NUMBER = 0x2504;
constexpr HDenum HD_NOMINAL_MAX_FORCE = 0x2603;
constexpr HDenum HD_CURRENT_FORCE = 0x2700;
constexpr HDenum HD_FORCE_OUTPUT = 0x4000;
constexpr HDenum HD_CALIBRATION_OK = 0x5000;
constexpr HDenum HD_CALIBRATION_NEEDS_UPDATE = 0x5001;
constexpr HDenum HD_CALIBRATION_NEEDS_MANUAL_INPUT = 0x5002;
constexpr HDenum HD_CALIBRATION_AUTO = 1;
constexpr HDCallbackCode HD_CALLBACK_DONE = 0;
constexpr HDCallbackCode HD_CALLBACK_CONTINUE = 1;
constexpr unsigned short HD_MAX_SCHEDULER_PRIORITY = 0xFFFF;
constexpr unsigned short HD_DEFAULT_SCHEDULER_PRIORITY = 0x7FFF;

using InitDevice = HHD (*)(const char* config);
using DisableDevice = void (*)(HHD);
using MakeCurrentDevice = void (*)(HHD);
using BeginFrame = void (*)(HHD);
using EndFrame = void (*)(HHD);
using GetDoublev = void (*)(HDenum, double*);
using GetIntegerv = void (*)(HDenum, int*);
using SetDoublev = void (*)(HDenum, const double*);
using GetString = const char* (*)(HDenum);
using Enable = void (*)(HDenum);
using StartScheduler = void (*)();
using StopScheduler = void (*)();
using ScheduleAsynchronous = HDSchedulerHandle (*)(HDSchedulerCallback, void* user, unsigned short priority);
using ScheduleSynchronous = void (*)(HDSchedulerCallback, void* user, unsigned short priority);
using Unschedule = void (*)(HDSchedulerHandle);
using GetError = HDErrorInfo (*)();
using GetErrorString = const char* (*)(HDerror);
using CheckCalibration = HDenum (*)();
using UpdateCalibration = void (*)(HDenum style);

} // namespace vox::haptics::hd
