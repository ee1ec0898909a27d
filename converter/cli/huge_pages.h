// The segmorph tool starts itself again, once, with glibc's transparent huge pages for its large buffers.
#pragma once

namespace segmorph {

// Large buffers (a production cache's frames are gigabytes) are first touched page by page, and with 4 KiB pages
// each touch is a page fault: on the machine the benchmarks run on, a third of a 200k-vertex encode's time. See
// huge_pages.cpp for when the tool restarts itself with glibc.malloc.hugetlb=1 and when it does not. Returns only
// when it does not restart (or the restart failed).
void use_transparent_huge_pages(char** argv);

}  // namespace segmorph
