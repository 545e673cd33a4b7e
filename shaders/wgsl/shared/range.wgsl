// A dispatch over a range (clothlab_engine::recipe::Command::Range): `first` and `count` in
// the immediates (push constants; uniforms on GL), one dispatch per range.

struct PassRange {
    first: u32,
    count: u32,
}
var<immediate> pass_range: PassRange;
