// lens, converted from a kdrt scene by kdrt-bench povray (500x500).
// Render: povray +W500 +H500 -D -A +FN File_Gamma=1.0 +I<this file>
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 15 ambient_light rgb <0.1, 0.1, 0.1> }
background { color rgb <0.25, 0.28, 0.32> }
camera {
  perspective
  location <0, 0.3, -4>
  sky <0, 1, 0>
  up y
  right -x*1
  angle 50
  look_at <0, 0, 2>
}
light_source { <4, 6, -6> color rgb <1, 1, 1> }
#declare M0_blue = material {
  texture {
    pigment { color rgb <0.2, 0.3, 0.95> }
    finish { ambient 0.9 diffuse 0.9 phong 0.4 phong_size 40 }
  }
}
#declare M1_red = material {
  texture {
    pigment { color rgb <0.95, 0.2, 0.2> }
    finish { ambient 0.9 diffuse 0.9 phong 0.4 phong_size 40 }
  }
}
#declare M2_glass = material {
  texture {
    pigment { color rgbt <1, 1, 1, 0.9> }
    finish { ambient 0.05 diffuse 0.05 phong 0.9 phong_size 120 reflection { 0.1 } }
  }
  interior { ior 1.5 }
}
sphere { <-1.1, 0, 4>, 1 material { M0_blue } }
sphere { <1.1, 0, 4>, 1 material { M1_red } }
sphere { <0, 0, 0.5>, 0.9 material { M2_glass } }
