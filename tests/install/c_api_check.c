/* A C99 program against the installed decoder, built with pkg-config's flags (tests/install/check_install.sh): the
 * header is C, the library links from C (with --static, its C++ runtime comes from Libs.private) and answers. */
#include <segmorph/decoder_c.h>
#include <stdio.h>
#include <string.h>

int main(void) {
  const unsigned char not_a_stream[] = {'S', 'G', 'M', 'A', 9, 0, 0, 0, 0, 0};
  const float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t indices[] = {0, 1, 2};
  segmorph_decoder* decoder = segmorph_decoder_create();
  segmorph_status status;
  if (!decoder) return 1;
  if (segmorph_version() != SEGMORPH_VERSION) {
    fprintf(stderr, "c_api_check: the library is version %d, the header %d\n", segmorph_version(), SEGMORPH_VERSION);
    return 1;
  }
  status = segmorph_decoder_open(decoder, not_a_stream, sizeof(not_a_stream), positions, 3, indices, 3);
  if (status != SEGMORPH_STATUS_UNSUPPORTED || strlen(segmorph_decoder_message(decoder)) == 0) {
    fprintf(stderr, "c_api_check: a version-9 stream gave '%s': %s\n", segmorph_status_name(status),
            segmorph_decoder_message(decoder));
    return 1;
  }
  printf("c_api_check: segmorph %d, stream versions %d to %d: %s\n", segmorph_version(), SEGMORPH_STREAM_VERSION_MIN,
         SEGMORPH_STREAM_VERSION_MAX, segmorph_decoder_message(decoder));
  segmorph_decoder_destroy(decoder);
  return 0;
}
