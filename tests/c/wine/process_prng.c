/* Test shim for Debian's wine 8.0, which lacks bcryptprimitives.dll: Rust's
 * standard library imports ProcessPrng from it for random numbers (hash
 * seeds). Built as bcryptprimitives.dll beside the test master, it serves
 * ProcessPrng from RtlGenRandom (advapi32's SystemFunction036). Windows 10
 * and 11 have the real one; nothing of this ships in an FMU. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG chunk = length > 0x40000000 ? 0x40000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk)) return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
