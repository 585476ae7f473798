% expected_all_types — the lnmatlab/all_types sample both directions of the round-trip tests
% use (tests/python/matlab/values.py holds the same values for the Python side).
function s = expected_all_types()
  s = struct();
  s.c = 'A';
  s.name = 'hello octave';
  s.i8 = int8(-128);
  s.u8 = uint8(255);
  s.i16 = int16(-32768);
  s.u16 = uint16(65535);
  s.i32 = intmin('int32');
  s.u32 = intmax('uint32');
  s.i64 = intmin('int64');
  s.u64 = intmax('uint64');
  s.f32 = single(1.5);
  s.f64 = -2.25e100;
  s.ai8 = int8([-1, 127]);
  s.au8 = uint8([0, 1, 255]);
  s.ai16 = int16([-2, 300]);
  s.au16 = uint16([1, 60000]);
  s.ai32 = int32([-70000, 70000]);
  s.au32 = uint32([0, 4000000000]);
  s.ai64 = [intmin('int64'), intmax('int64')];
  s.au64 = [uint64(0), intmax('uint64')];
  s.af32 = single([0.25, -3.5]);
  s.af64 = [1/3, -1e-300, Inf, 42];
  s.inner = struct('xyz', single([1, 2, 3]), 'flags', uint8(7));
  s.points = struct('xyz', {single([4, 5, 6]), single([7, 8, 9])}, 'flags', {uint8(8), uint8(9)});
end
