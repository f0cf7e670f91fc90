#pragma once
// The part of the Force Dimension DHD API (libdhd.so) this program calls, declared here because
// the vendor's headers may not be redistributed. The C++ API's default device argument is passed
// explicitly as the last `char id` (-1: the default device). Positions in metres, forces in N.

namespace vox::haptics::dhd {

constexpr char k_default_device = -1;
constexpr int DHD_NO_ERROR = 0;

using GetDeviceCount = int (*)();
using Open = int (*)();
using OpenID = int (*)(char index);
using Close = int (*)(char id);
using GetSystemName = const char* (*)(char id);
using GetSerialNumber = int (*)(unsigned short* serial, char id);
using GetPosition = int (*)(double* x, double* y, double* z, char id);
using GetOrientationFrame = int (*)(double matrix[3][3], char id);
using GetButtonMask = unsigned int (*)(char id);
using SetForce = int (*)(double fx, double fy, double fz, char id);
using SetForceAndTorque = int (*)(double fx, double fy, double fz, double tx, double ty, double tz, char id);
using EnableForce = int (*)(unsigned char on, char id);
using GetMaxForce = double (*)(char id);
using ErrorGetLast = int (*)();
using ErrorGetLastStr = const char* (*)();
using ErrorGetStr = const char* (*)(int error);

} // namespace vox::haptics::dhd
