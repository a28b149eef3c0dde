/* gi_dump: `--dump-stages DIR` — every stage of a frame as an image, with
 * the one-line captions the stepper of `softgi view` shows, so people
 * without a display can step through a frame. The pictures are gi_view's
 * (one implementation for the dump and the viewer). */
#include "gi_frame.h"
#include "gi_view.h"

pf_result gi_frame_dump_stages(const gi_frame *f, const char *dir, pf_error *err)
{
    gi_view_settings s = {0.0f, 0};
    return gi_view_dump(f, dir, &s, err);
}
