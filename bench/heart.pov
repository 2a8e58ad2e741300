// The benchmark heart for POV-Ray 3.7: the same heart, camera, light and image size as
// bench/heart.scene. POV-Ray is left-handed with y up, so kardia's (x, y, z) is written here
// as <x, z, y>; the polynomial is the paper's heart
//   (2X^2 + Y^2 + Z^2 - 1)^3 - (0.1X^2 + Y^2) Z^3   with X = x, Y = z, Z = y,
// expanded into its 22 monomials, solved with POV-Ray's Sturm-sequence root finder.
#version 3.7;
global_settings { assumed_gamma 1.0 ambient_light rgb 1 }
background { rgb 0 }
camera {
  perspective
  location <4.5, 0.1, 0>
  look_at <0, 0.1, 0>
  sky <0, 1, 0>
  right x * image_width / image_height
  angle 35
}
light_source { <5, 4, -3> color rgb 1 }
polynomial {
  6,
  xyz(6,0,0): 8, xyz(4,2,0): 12, xyz(4,0,2): 12, xyz(4,0,0): -12,
  xyz(2,4,0): 6, xyz(2,3,0): -0.1, xyz(2,2,2): 12, xyz(2,2,0): -12,
  xyz(2,0,4): 6, xyz(2,0,2): -12, xyz(2,0,0): 6,
  xyz(0,6,0): 1, xyz(0,4,2): 3, xyz(0,4,0): -3, xyz(0,3,2): -1,
  xyz(0,2,4): 3, xyz(0,2,2): -6, xyz(0,2,0): 3,
  xyz(0,0,6): 1, xyz(0,0,4): -3, xyz(0,0,2): 3, xyz(0,0,0): -1
  sturm
  bounded_by { box { <-0.72, -1.01, -1.14>, <0.72, 1.24, 1.14> } }
  texture {
    pigment { rgb <0.8, 0.1, 0.1> }
    finish { ambient 0.1 diffuse 1 phong 0.4 phong_size 40 }
  }
}
