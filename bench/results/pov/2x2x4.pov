// 2x2x4, converted from a kdrt scene by kdrt-bench povray (500x500).
// Render: povray +W500 +H500 -D -A +FN File_Gamma=1.0 +I<this file>
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 15 ambient_light rgb <0.1, 0.1, 0.1> }
background { color rgb <0.05, 0.05, 0.12> }
camera {
  perspective
  location <4, 5.5, -5>
  sky <0, 1, 0>
  up y
  right -x*1
  angle 40
  look_at <0, 0, 0>
}
light_source { <5, 8, -6> color rgb <1, 1, 1> }
#declare M0_ball0 = material {
  texture {
    pigment { color rgb <0.9, 0.2, 0.2> }
    finish { ambient 0.8 diffuse 0.8 phong 0.5 phong_size 40 reflection { 0.3 } }
  }
}
#declare M1_ball1 = material {
  texture {
    pigment { color rgb <0.2, 0.8, 0.3> }
    finish { ambient 0.8 diffuse 0.8 phong 0.5 phong_size 40 reflection { 0.3 } }
  }
}
#declare M2_ball2 = material {
  texture {
    pigment { color rgb <0.2, 0.4, 0.95> }
    finish { ambient 0.8 diffuse 0.8 phong 0.5 phong_size 40 reflection { 0.3 } }
  }
}
#declare M3_ball3 = material {
  texture {
    pigment { color rgb <0.95, 0.8, 0.2> }
    finish { ambient 0.8 diffuse 0.8 phong 0.5 phong_size 40 reflection { 0.3 } }
  }
}
sphere { <-0.5, -0.5, -1.5>, 0.45 material { M0_ball0 } }
sphere { <0.5, -0.5, -1.5>, 0.45 material { M1_ball1 } }
sphere { <-0.5, 0.5, -1.5>, 0.45 material { M2_ball2 } }
sphere { <0.5, 0.5, -1.5>, 0.45 material { M3_ball3 } }
sphere { <-0.5, -0.5, -0.5>, 0.45 material { M0_ball0 } }
sphere { <0.5, -0.5, -0.5>, 0.45 material { M1_ball1 } }
sphere { <-0.5, 0.5, -0.5>, 0.45 material { M2_ball2 } }
sphere { <0.5, 0.5, -0.5>, 0.45 material { M3_ball3 } }
sphere { <-0.5, -0.5, 0.5>, 0.45 material { M0_ball0 } }
sphere { <0.5, -0.5, 0.5>, 0.45 material { M1_ball1 } }
sphere { <-0.5, 0.5, 0.5>, 0.45 material { M2_ball2 } }
sphere { <0.5, 0.5, 0.5>, 0.45 material { M3_ball3 } }
sphere { <-0.5, -0.5, 1.5>, 0.45 material { M0_ball0 } }
sphere { <0.5, -0.5, 1.5>, 0.45 material { M1_ball1 } }
sphere { <-0.5, 0.5, 1.5>, 0.45 material { M2_ball2 } }
sphere { <0.5, 0.5, 1.5>, 0.45 material { M3_ball3 } }
